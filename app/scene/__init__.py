"""Scene descriptions: what scene files say (description.py), read from pathtrace's TOML format
(toml_reader.py) with meshes from common formats (meshes.py), or built in (builtin.py); the
description's parts that are no type registry of their own: the environment (environment.py),
media (media.py), spectra as RGB (spectra.py), and the lists read by name (named.py)."""

from pathlib import Path

from pathtrace.errors import UserError, cut, did_you_mean, grouped_warnings
from pathtrace.io.files import missing, shown
from pathtrace.scene.description import Mesh, RenderSettings, Scene, SceneBuilder, diffuse, emitter, phong

__all__ = ["Mesh", "RenderSettings", "Scene", "SceneBuilder", "diffuse", "emitter", "phong",
           "load_scene"]


GENERIC_NAMES = ("scene", "scene-v3", "scene-v4")   # file names that say nothing of their scene, such as
                                                   # those of Bitterli's collection (coffee/pbrt/scene-v4.pbrt,
GENERIC_FOLDERS = ("pbrt", "pbrt-v4", "mitsuba")   # coffee/mitsuba/scene.xml), and folders that hold one
                                                   # format's file of a scene


def named(scene: Scene, path: Path) -> Scene:
    """A scene read from a file with a generic name (GENERIC_NAMES) is named after its folder
    (the one above, where that is a format's, GENERIC_FOLDERS): the window's title, the panel,
    the progress bar and screenshots then say which it is."""
    stem = path.name.lower().removesuffix(".gz").rsplit(".", 1)[0]
    folder = path.resolve().parent
    while folder.name.lower() in GENERIC_FOLDERS and folder.parent != folder:
        folder = folder.parent
    if stem in GENERIC_NAMES and folder.name:
        scene.name = folder.name
    return scene


def load_scene(name_or_path: str) -> Scene:
    """A scene file path or a built-in scene's name: the two are interchangeable. Only the
    reader a scene needs is imported (each is a few tens of milliseconds of a command's start).
    Its warnings are told each once, with a count of those like it (grouped_warnings). A scene
    read before, whose files are unchanged, comes from pathtrace.scene.read_cache."""
    from pathtrace.scene.read_cache import cached_read
    with grouped_warnings():
        return cached_read(name_or_path, _read_scene)


def find_scene(name_or_path: str):
    """Raises, in one line, as load_scene would, where `name_or_path` names no scene file that
    pathtrace reads and no built-in scene; reads and builds nothing (the viewer without a display
    says so before it says how to render headless)."""
    _reader(name_or_path)


def _read_scene(name_or_path: str) -> Scene:
    return _reader(name_or_path)()


SCENE_SUFFIXES = (".toml", ".xml", ".pbrt", ".pbrt.gz")     # what the readers read, by name


def _reader(name_or_path: str):
    """What reads the scene `name_or_path`, a function of no arguments; or the one-line error."""
    if not str(name_or_path).strip():     # Path("") is the current folder, which no reader means
        raise UserError("no scene given: the scene's name or path is empty")
    path = Path(name_or_path)
    try:
        exists = path.exists()
    except OSError as e:     # a name too long for the file system, say
        raise UserError(f"{cut(shown(path), 80)}: {e.strerror}") from None
    pbrt = path.name.lower().endswith((".pbrt", ".pbrt.gz"))
    # a name written as a file's path (with a suffix or a folder; no built-in scene's name has
    # either) is a file that is not there
    if not exists and (path.suffix or len(path.parts) > 1):
        raise UserError(f"{missing(path, 'scene file')}{_nearest_scene_file(path)}")
    if path.suffix.lower() == ".xml":
        def read_xml():
            from pathtrace.scene.mitsuba import read_mitsuba_file
            return named(read_mitsuba_file(path), path)
        return read_xml
    if pbrt:
        def read_pbrt():
            from pathtrace.scene.pbrt import read_pbrt_file
            return named(read_pbrt_file(path), path)
        return read_pbrt
    if exists:      # a file of a built-in scene's name is the file
        if path.is_file() and path.suffix.lower() != ".toml":
            raise UserError(f"{cut(shown(path), 100)}: not a scene file: pathtrace reads .toml (its own format), "
                            ".xml (Mitsuba 3) and .pbrt or .pbrt.gz (pbrt-v4)")

        def read_toml():
            from pathtrace.scene.toml_reader import read_scene_file
            return read_scene_file(path)        # which refuses a folder, a fifo or a device in one line
        return read_toml
    from pathtrace.scene.builtin import BUILTIN_SCENES, MAX_GENERATED, builtin_maker
    make = builtin_maker(name_or_path)
    if make is not None:
        return make
    raise UserError(f"{cut(shown(name_or_path), 100)}: neither a scene file nor a built-in scene"
                    f"{did_you_mean(str(name_or_path), BUILTIN_SCENES)} (built-ins: {', '.join(BUILTIN_SCENES)}; "
                    f"generated: spheresN[-diffuse] and heightfieldN, N from 1 to {MAX_GENERATED // 1_000_000}M, "
                    "e.g. spheres512k)")


def _nearest_scene_file(path: Path) -> str:
    """"; did you mean X?" where the folder of a missing scene file holds one of a name close to
    its (a misspelt extension: scene.pbr), compared without their extensions, so that a folder's
    only scene file is not offered for any name ending alike; of the files of that stem, the one
    whose whole name is nearest (cbox.pbrt for cbox.pbrt.gz, beside cbox.xml); else ""."""
    try:
        names = sorted(p.name for p in path.parent.iterdir() if p.name.lower().endswith(SCENE_SUFFIXES))
    except OSError:
        return ""
    import difflib
    close = difflib.get_close_matches(path.name.split(".")[0], {name.split(".")[0] for name in names}, n=1)
    if not close:                                   # (did_you_mean's measure)
        return ""
    alike = [name for name in names if name.split(".")[0] == close[0]]
    nearest = max(alike, key=lambda name: difflib.SequenceMatcher(None, path.name, name).ratio())
    return f"; did you mean {nearest!r}?"
