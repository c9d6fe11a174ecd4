"""The parameter tables of docs/scene-format.md, generated from the types' declarations
(app/parameters.py): each block between `<!-- parameters: KIND -->` and `<!-- end parameters -->`
is the tables of the types of KIND (lights, environment, materials, textures, media, shapes, cameras,
filters, surface: what any material carries, render: the [render] table), one per type, with a column for
each format that has the type. `python -m pathtrace.scene.format_tables` rewrites the file;
tests/test_parameters.py fails where the file and the declarations differ."""

import re
import sys
from pathlib import Path

from pathtrace.cameras import CAMERAS
from pathtrace.lights import DELTA_LIGHTS
from pathtrace.materials import BSDFS
from pathtrace.scene.environment import Environment
from pathtrace.scene.media import Medium
from pathtrace.parameters import parameter_table
from pathtrace.textures import TEXTURES

DOC = Path(__file__).resolve().parents[2] / "docs" / "scene-format.md"
MARKER = re.compile(r"(<!-- parameters: (\w+) -->\n).*?(<!-- end parameters -->)", re.S)
NOTE = ("Generated from the types' declarations (`python -m pathtrace.scene.format_tables`). A blank "
        "default is optional; † marks a value the reader converts (pbrt-v4's power, a spot's cone); "
        "\"its frame\": the element's transform places it (Mitsuba's `to_world`); a row with no TOML name is "
        "a format's own, which the type maps onto its parameters (pbrt-v4's roughness onto alpha).\n")


def _types(kind: str) -> list:
    """(name, its formats' names, doc, parameters) of each type of KIND."""
    if kind == "lights":
        return [(c.name, c.formats, " ".join(sys.modules[c.__module__].__doc__.split()), c.parameters)
                for c in DELTA_LIGHTS.values()]
    if kind == "materials":
        return [(b.name, b.formats, b.doc, b.params + b.format_only) for b in BSDFS.values() if b.params]
    if kind == "textures":
        return [(t.name, t.formats, t.doc, t.parameters + t.format_only) for t in TEXTURES.values()]
    if kind == "media":
        return [("homogeneous", Medium.formats, "", Medium.parameters)]
    if kind == "cameras":
        return [(c.type, {f: getattr(c, f) for f in ("mitsuba", "pbrt") if getattr(c, f)},
                 " ".join(sys.modules[c.__module__].__doc__.split())
                 + ("" if c.importance else " BDPT cannot render through it yet (no importance)."),
                 c.parameters + c.format_only)
                for c in CAMERAS.values()]
    if kind == "filters":
        from pathtrace.filters import TYPES
        return [(t.name, t.formats, t.doc, t.parameters) for t in TYPES.values()]
    if kind == "environment":
        return [(Environment.name, Environment.formats, Environment.doc, Environment.parameters)]
    if kind == "surface":
        from pathtrace.materials.surface import MITSUBA_WRAPPERS, PBRT_MAPS, SURFACE
        return [("any material", {"mitsuba": MITSUBA_WRAPPERS, "pbrt": "Shape"}, "", SURFACE + PBRT_MAPS)]
    if kind == "render":
        from pathtrace.scene.settings import RENDER
        return [("render", {"mitsuba": ("film", "sampler", "integrator"), "pbrt": ("Film", "Sampler", "Integrator")},
                 "", RENDER)]
    if kind == "shapes":
        from pathtrace.shapes import SHAPES
        return [(k.name, k.formats, k.doc, k.parameters + k.mitsuba_parameters) for k in SHAPES.values()]
    raise ValueError(f"no parameter tables of {kind!r}")


def section(kind: str) -> str:
    out = [NOTE]
    for name, formats, doc, parameters in _types(kind):
        others = ", ".join(f"{label} " + " and ".join(f"`{n}`" for n in ((formats[f],) if isinstance(formats[f], str)
                                                                         else formats[f]))
                           for f, label in (("mitsuba", "Mitsuba 3"), ("pbrt", "pbrt-v4")) if f in formats)
        out.append(f"\n#### `{name}`" + (f" ({others})" if others else " (pathtrace's own)") + "\n\n"
                   + (f"{doc}\n\n" if doc else "")
                   + parameter_table(parameters, ("toml", *(f for f in ("mitsuba", "pbrt") if f in formats))))
    return "".join(out)


def update(text: str) -> str:
    """The text with each marked block regenerated."""
    return MARKER.sub(lambda m: m.group(1) + section(m.group(2)) + m.group(3), text)


if __name__ == "__main__":
    DOC.write_text(update(DOC.read_text()))
