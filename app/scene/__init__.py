"""Scene descriptions: what scene files say (description.py), read from pathtrace's TOML format
(toml_reader.py) with meshes from common formats (meshes.py), or built in (builtin.py)."""

from pathlib import Path

from pathtrace.errors import UserError, cut, grouped_warnings
from pathtrace.files import shown
from pathtrace.scene.description import Mesh, RenderSettings, Scene, SceneBuilder, diffuse, emitter, phong

__all__ = ["Mesh", "RenderSettings", "Scene", "SceneBuilder", "diffuse", "emitter", "phong",
           "load_scene"]


def load_scene(name_or_path: str) -> Scene:
    """A scene file path or a built-in scene's name: the two are interchangeable. Only the
    reader a scene needs is imported (each is a few tens of milliseconds of a command's start).
    Its warnings are told each once, with a count of those like it (grouped_warnings)."""
    with grouped_warnings():
        return _read_scene(name_or_path)


def _read_scene(name_or_path: str) -> Scene:
    path = Path(name_or_path)
    if path.suffix.lower() == ".xml":
        from pathtrace.scene.mitsuba import read_mitsuba_file
        return read_mitsuba_file(path)
    if path.name.lower().endswith((".pbrt", ".pbrt.gz")):
        from pathtrace.scene.pbrt import read_pbrt_file
        return read_pbrt_file(path)
    try:
        exists = path.exists()
    except OSError as e:     # a name too long for the file system, say
        raise UserError(f"{cut(shown(path), 80)}: {e.strerror}") from None
    if path.suffix == ".toml" or exists:
        from pathtrace.scene.toml_reader import read_scene_file
        return read_scene_file(path)
    from pathtrace.scene.builtin import BUILTIN_SCENES, builtin_scene
    scene = builtin_scene(name_or_path)
    if scene is not None:
        return scene
    raise UserError(f"{cut(shown(name_or_path), 100)}: neither a scene file nor a built-in scene "
                    f"(built-ins: {', '.join(BUILTIN_SCENES)})")
