"""pbrt-v4 scene files (pbrt-v4's format, docs/pbrt.md): tokens.py reads the syntax, reader.py
the directives and graphics state, materials.py maps pbrt's materials and textures,
equal_area.py its environment maps."""

from pathtrace.scene.pbrt.reader import read_pbrt_file

__all__ = ["read_pbrt_file"]
