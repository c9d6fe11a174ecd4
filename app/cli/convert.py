"""`pathtrace convert`: a scene of any format written as pathtrace TOML, with its side files."""

import contextlib
import os
import sys
from dataclasses import replace
from pathlib import Path

from pathtrace.cli.interrupts import FinalWrite
from pathtrace.cli.options import SCENES_EPILOG
from pathtrace.errors import UserError

def _same_file(a, b) -> bool:
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):        # either missing (or a name no file can have)
        return False


def cmd_convert(args):
    """All or nothing: the TOML and its side files (NAME.environment.exr, NAME.meshes/,
    NAME.imageK.exr) are checked, then written under temporary names and renamed into place
    together, so that a failure (a read-only folder, a full disk, a FIFO where a file goes)
    leaves none of them."""
    from pathtrace.api import load
    from pathtrace.io.images import Staged, _write_exr, check_writable
    from pathtrace.scene.toml_writer import scene_toml

    out = Path(args.output)
    if out.suffix.lower() != ".toml":
        raise UserError(f"--output: {out}: pathtrace writes scenes as .toml")
    if _same_file(out, args.scene):      # a hand-written file would be replaced by its conversion
        raise UserError(f"--output: {out}: is the scene being converted; give another file")
    scene = load(args.scene)
    check_writable(out, "--output", formats=None)
    env = scene.environment
    map_path = out.with_name(out.stem + ".environment.exr") if env.resampled else None
    if map_path:             # the map as pathtrace reads it, beside the scene
        check_writable(map_path, "--output", formats=(".exr",))
    meshes = mesh_files(scene, out)
    images = image_files(scene, out)
    for path, _ in images:
        check_writable(path, "--output", formats=(".exr",))
    folder = out.with_name(out.stem + ".meshes")
    if meshes and os.path.lexists(folder) and not folder.is_dir():
        raise UserError(f"--output: '{folder}' exists and is not a folder, where the meshes go")
    made_folder = bool(meshes) and not folder.exists()
    try:
        with Staged() as staged:
            if made_folder:
                folder.mkdir()
            for path, _ in meshes:
                check_writable(path, "--output", formats=None)
            if map_path:
                staged.add(map_path, lambda tmp: _write_exr(tmp, env.image), "--output")
                scene.environment = replace(env, source=str(map_path), resampled=False)
            for path, mesh in meshes:
                staged.add(path, lambda tmp, m=mesh: write_mesh_file(tmp, m), "--output")
            for path, image in images:
                staged.add(path, lambda tmp, i=image: _write_exr(tmp, i.rgb()), "--output")
                image.path = str(path)
            text = scene_toml(scene, out)
            staged.add(out, lambda tmp: write_text_file(tmp, text), "--output")
            with FinalWrite():
                staged.commit()
    except BaseException:
        if made_folder:
            with contextlib.suppress(OSError):
                folder.rmdir()       # empty: its files were only staged
        raise
    if map_path:
        print(f"wrote {map_path}", file=sys.stderr)
    if meshes:
        print(f"wrote {len(meshes)} mesh{'' if len(meshes) == 1 else 'es'} to {folder}/", file=sys.stderr)
    for path, _ in images:
        print(f"wrote {path}", file=sys.stderr)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def mesh_files(scene, out: Path, inline_faces: int = 1000) -> list:
    """(path, mesh) of the meshes that came from no file (a pbrt scene's, whose faces and uvs
    the reader turned), to be written as PLY files beside the TOML where they have normals (an
    inline mesh has none) or more than `inline_faces` faces; each mesh is set to refer to its
    file, as the TOML will."""
    import numpy as np

    from pathtrace.scene.description import MeshFile

    folder = out.with_name(out.stem + ".meshes")
    found = []
    objects = scene.instances.objects if scene.instances is not None else []
    for k, mesh in enumerate(scene.meshes + [m for o in objects for m in o.meshes]):
        if mesh.file is not None or (mesh.normals is None and len(mesh.faces) <= inline_faces):
            continue
        path = folder / f"{k:04d}.ply"
        found.append((path, mesh))
        mesh.file = MeshFile(str(path), np.eye(4))
    return found


def image_files(scene, out: Path) -> list:
    """(path, image) of the textures' images that no file holds (a pbrt imagemap's `invert`,
    baked into its texels), to be written beside the TOML as EXR files: NAME.imageK.exr, their
    rgb (no texture reads a bitmap's alpha: kernels/textures/bitmap.cl)."""
    found = []
    for t in scene.materials.all_textures():
        image = t.params.get("image") if t.type == "bitmap" else None
        if image is not None and not image.path and not any(image is i for _, i in found):
            found.append((out.with_name(f"{out.stem}.image{len(found)}.exr"), image))
    return found


def write_text_file(path, text: str) -> bool:
    Path(path).write_text(text)
    return True


def write_mesh_file(path, mesh) -> bool:
    from pathtrace.scene.meshes import write_ply
    write_ply(path, mesh.vertices, mesh.faces, mesh.normals, mesh.uvs)
    return True


def add_parser(sub):
    """The `convert` command's parser."""
    p = sub.add_parser("convert", help="write a scene (a Mitsuba 3 .xml or pbrt-v4 .pbrt file, say) as pathtrace TOML",
                       epilog=SCENES_EPILOG)
    p.add_argument("scene", help="a .xml, .pbrt or .toml scene file or a built-in scene name")
    p.add_argument("-o", "--output", required=True, metavar="FILE.toml",
                   help="the TOML file to write: mesh files the scene reads as they are stay where they "
                        "are, referenced; meshes it changed on reading (a pbrt file's) or gave inline are "
                        "written as PLY files into FILE.meshes/ beside it")
    p.set_defaults(func=cmd_convert)
