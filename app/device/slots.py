"""Slots: where a type's values lie in the packed rows the kernels read (a material's MATERIAL row,
a light's LIGHT row), declared once on the host. The kernels read each through an accessor
generated from its declaration, <TYPE>_<NAME>(x) (app/materials/registry.py: tag_source;
app/lights/registry.py: kernel_parts), and the host packs and unpacks through read_slot and
write_slot, so that a layout is written nowhere else (tests/test_types.py checks both sides).

A slot names floats of the fields p0, p1, p2 (float4s) and, in a material, its table (16
floats): "p0.xyz" (a colour) or "p1.w" or "p1.zw", "table[3]", "table[7:10]" (a colour), or
"table", all of it (a tabulated function)."""

import re
from dataclasses import dataclass

SLOT_SYNTAX = re.compile(r"(p[012])\.([xyzw]+)|table(?:\[(\d+)(?::(\d+))?\])?")


@dataclass(frozen=True)
class Slot:
    """A slot that pack() computes from a type's parameters rather than takes from one (Phong's
    lobe choice, a spot light's cosines), or one of a type whose values are not Parameters:
    declared beside the parameters so that the kernels read it, as they read those, through the
    accessor generated from it; doc gives its meaning or formula."""
    name: str
    slot: str
    doc: str
    packed: bool = True     # written by pack(); False: by the table that holds the rows (a blend's)


def slot_floats(slot: str) -> list:
    """The floats a slot names, counted over p0, p1, p2 and the table (p0.x: 0, table[0]: 12):
    'p1.xyz' -> [4, 5, 6], 'table[7:10]' -> [19, 20, 21]."""
    match = SLOT_SYNTAX.fullmatch(slot)
    if match is None:
        raise ValueError(f"slot {slot!r}: not of the form p0.xyz, p1.w, table[3], table[7:10] or table")
    field, components, first, end = match.groups()
    if field:
        return [4 * int(field[1]) + "xyzw".index(c) for c in components]
    if first is None:
        return list(range(12, 28))
    return list(range(12 + int(first), 12 + int(end if end is not None else int(first) + 1)))


def slot_accessor(slot: str, row: str = "m") -> str:
    """The C expression of a slot of the row pointer `row`: a float, a floatN, or (the whole
    table) its array."""
    floats = slot_floats(slot)
    if slot.startswith("p"):
        return f"(({row})->{slot})"
    if slot == "table":
        return f"(({row})->table)"
    reads = ", ".join(f"({row})->table[{f - 12}]" for f in floats)
    return f"(({row})->table[{floats[0] - 12}])" if len(floats) == 1 else f"((float{len(floats)})({reads}))"


def _field_range(slot: str) -> tuple:
    """(field, first index in it, width) of a slot."""
    floats = slot_floats(slot)
    field = "table" if floats[0] >= 12 else f"p{floats[0] // 4}"
    return field, floats[0] - (12 if field == "table" else 4 * int(field[1])), len(floats)


def read_slot(rows, slot: str):
    """A slot's values in rows (or one row): a number's as (n,), several floats' as (n, width)."""
    field, first, width = _field_range(slot)
    values = rows[field][..., first:first + width]
    return values[..., 0] if width == 1 else values


def write_slot(rows, slot: str, values):
    """Writes values (one for all rows, or one per row) into a slot of rows (or of one row)."""
    field, first, width = _field_range(slot)
    if width == 1:
        rows[field][..., first] = values
    else:
        rows[field][..., first:first + width] = values
