"""The parameter names the formats' own renderers know, per type, and what a reader does with a
parameter it did not read. pbrt-v4 stops at a parameter that no Create() function looked up
(ParameterDictionary::ReportUnused, src/pbrt/paramdict.cpp: ErrorExit '"name": unused
parameter'), and Mitsuba 3 at a property its plugin never queried (instantiate_node,
src/core/xml.cpp: 'unreferenced property'). So does pathtrace, where the renderer does not
know the name for that type: a misspelt `radisu` is one line naming the file, the line, the
type and the parameter, with the known name it is closest to. A name the renderer knows and
pathtrace does not implement is warned of instead, once per name and type in a file, so that
real scenes still load. Types alike: a type the renderer has and pathtrace has not is warned of and
replaced or left out, where the reader says; one the renderer has not either (a misspelt `difuse`)
is refused, as the renderer refuses it (refuse_unknown_type).

The lists, extracted from the renderers' sources and checked against them
(tests/test_pbrt_parameter_names.py, tests/test_mitsuba_parameter_names.py), are
app/scene/pbrt/known_parameters.json ('pbrt-v4') and app/scene/mitsuba_known_properties.json
('mitsuba3'), keyed "category type" ("shape sphere", "bsdf diffuse"), and each file's 'types', the
renderer's types per category."""

import json
from functools import cache
from pathlib import Path

from pathtrace.errors import UserError, cut, did_you_mean

_FILES = {"pbrt": ("pbrt/known_parameters.json", "pbrt-v4"), "mitsuba": ("mitsuba_known_properties.json", "mitsuba3")}
RENDERER = {"pbrt": "pbrt-v4", "mitsuba": "Mitsuba 3"}


@cache
def document(fmt: str) -> dict:
    """The list's file of the format fmt ("pbrt", "mitsuba"): its 'about', its 'sources' and its
    table."""
    return json.loads((Path(__file__).parent / _FILES[fmt][0]).read_text())


def table(fmt: str) -> dict:
    """{'category type': [the names the renderer reads]} of the format fmt."""
    return document(fmt)[_FILES[fmt][1]]


def known(fmt: str, key: str):
    """The names the renderer of fmt knows for the type `key`, or None where the list has no such
    type (a type pathtrace does not read, whose parameters are left out with it)."""
    return table(fmt).get(key)


def refuse_unknown_type(fmt: str, category: str, kind: str, where: str):
    """Refuses the type `kind` of the `category` ("shape", "bsdf") at `where` where the renderer of
    fmt has no such type (UserError, with the type it is closest to); else nothing, whether
    pathtrace has it or not."""
    types = document(fmt)["types"].get(category)
    if types is not None and kind not in types:
        renderer = RENDERER[fmt]
        raise UserError(f"{where}: {renderer} has no {category} type '{cut(kind)}', and refuses it"
                        f"{did_you_mean(kind, types, quoted=True)}")


class Unread:
    """The reader's verdict on the parameters of one file's elements that it did not read:
    refused where the renderer does not know them (UserError), else warned of once per type
    and name."""

    def __init__(self, fmt: str):
        self.fmt = fmt
        self.warned = set()

    def check(self, where: str, key: str, label: str, name: str, file: str, refusable=True) -> str | None:
        """The warning for the parameter `name` at `where` (file:line) of the type `key`
        ("shape sphere"), shown as `label` ("sphere shape"), the first time in `file`; None
        where it was warned of before. Refused where the renderer does not know the name,
        unless not `refusable` (an object the renderer may take by its place, not its name)."""
        names = known(self.fmt, key)
        renderer = RENDERER[self.fmt]
        noun = "parameter" if self.fmt == "pbrt" else "property"
        if refusable and names is not None and name not in names:
            raise UserError(f"{where}: '{cut(name)}' is not a {noun} of {renderer}'s {label}, which {renderer} "
                            f"refuses{did_you_mean(name, names, quoted=True)}")
        if (file, key, name) in self.warned:
            return None
        self.warned.add((file, key, name))
        return f"{where}: '{cut(name)}' is not a {noun} pathtrace's {label} reads; ignored"
