"""The NumPy dtypes of app/device/types.py match the device's layout of kernels/types.h, field by field
(so that swapped fields of equal size are caught too)."""

import re
from pathlib import Path

import numpy as np
import pytest

from pathtrace.device.types import (BVH_NODE, INSTANCE, LIGHT, LIGHT_NODE, MATERIAL, MEDIUM, PATH_RECORD, PHOTON,
                                    PHOTON_MAP, RENDER_PARAMS, TEXTURE, TEXTURE_BINDING, TRIANGLE)

STRUCTS = {
    "Material": MATERIAL,
    "Triangle": TRIANGLE,
    "RenderParams": RENDER_PARAMS,
    "Light": LIGHT,
    "LightNode": LIGHT_NODE,
    "BVHNode": BVH_NODE,
    "Texture": TEXTURE,
    "TextureBinding": TEXTURE_BINDING,
    "Medium": MEDIUM,
    "Instance": INSTANCE,
    "PathRecord": PATH_RECORD,
    "Photon": PHOTON,
    "PhotonMap": PHOTON_MAP,
}


def layout_source(name, dtype):
    lines = [f"out[0] = sizeof({name});"]
    lines += [f"out[{i + 1}] = (int)__builtin_offsetof({name}, {field});" for i, field in enumerate(dtype.names)]
    return f"kernel void layout_{name}(global int *out) {{ {' '.join(lines)} }}\n"


SOURCE = "".join(layout_source(n, d) for n, d in STRUCTS.items()) + \
    "kernel void layout_node(global int *out) { out[0] = sizeof(BVHNode); out[1] = sizeof(Sphere); }\n"


@pytest.mark.parametrize("name", list(STRUCTS))
def test_dtype_matches_device_layout(kernels, name):
    dtype = STRUCTS[name]
    out = np.zeros(len(dtype.names) + 1, np.int32)
    kernels(SOURCE)(f"layout_{name}", 1, out)
    assert out.tolist() == [dtype.itemsize] + [dtype.fields[f][1] for f in dtype.names]


def test_node_and_sphere_sizes(kernels):
    out = np.zeros(2, np.int32)
    kernels(SOURCE)("layout_node", 1, out)
    assert out.tolist() == [BVH_NODE.itemsize, 16]


# -- the MATERIAL slots each material type declares (Param.slot, BSDFType.derived), whose
#    accessors the kernels read (app/materials/registry.py: tag_source) --

KERNELS = Path(__file__).resolve().parent.parent / "kernels"
# Files that touch p0..p2 by index for every type alike: shading.cl writes a texture's value into
# the slot its binding names (the host's Param.slot, app/materials/table.py: slot_index).
GENERIC = {"shading.cl"}
# the light kernels, whose Light has p0..p2 of its own (app/lights/registry.py: kernel_parts)
LIGHT_FILES = sorted((KERNELS / "lights").glob("*.cl"))
RAW_SLOT = re.compile(r"(->|\.)\s*(p[012]|table)\b")


def code_of(path: Path) -> str:
    """A kernel file without its comments."""
    return re.sub(r"/\*.*?\*/|//[^\n]*", " ", path.read_text(), flags=re.S)


def material_kernel_files() -> list:
    """Every kernel file that may read a material, but the light kernels."""
    return [f for f in sorted(KERNELS.rglob("*.cl")) + sorted(KERNELS.rglob("*.h"))
            if f not in LIGHT_FILES and f.name not in GENERIC]


def each_slot():
    from pathtrace.materials import BSDFS
    for name, bsdf in BSDFS.items():
        for p in bsdf.params:
            if p.slot:
                yield name, bsdf, p.name, p.slot, p
        for d in bsdf.derived:
            yield name, bsdf, d.name, d.slot, d


def test_each_material_types_slots_are_distinct_floats_of_its_kind():
    """A parameter's slot holds its kind (a colour 3 floats, a number or bool 1), a textured
    one lies in p0..p2 (where the texture bindings write), and no two slots of a type overlap."""
    from pathtrace.device.slots import slot_floats
    taken = {}
    for name, _, slot_name, slot, p in each_slot():
        floats = slot_floats(slot)
        if hasattr(p, "kind"):
            assert len(floats) == (3 if p.kind == "color" else 1), (name, slot_name, slot)
            assert not p.texture or max(floats) < 12, (name, slot_name, slot)
        assert not set(floats) & set(taken.setdefault(name, [])), (name, slot_name, slot)
        taken[name] += floats


def packed_floats(bsdf, values, fill=0.0):
    from pathtrace.textures.texture import Texture
    rows = np.zeros(1, MATERIAL)
    for field in ("p0", "p1", "p2", "table"):
        rows[field] = fill
    bsdf.pack({k: (v if isinstance(v, (str, Texture)) else np.atleast_2d(v) if np.ndim(v) else np.atleast_1d(v))
               for k, v in values.items()}, rows)
    return np.concatenate([rows["p0"][0], rows["p1"][0], rows["p2"][0], rows["table"][0]])


def test_pack_writes_each_slotted_parameter_where_its_slot_says():
    """A texture's value is written into the slot at each hit (kernels/shading.cl), so pack must
    put the constant there too, as it is: the slot is the parameter's one place."""
    from pathtrace.materials import BSDFS
    from pathtrace.device.slots import slot_floats
    from pathtrace.textures.texture import Texture
    for name, bsdf in BSDFS.items():
        for example in bsdf.__class__.__dict__.get("examples", ()):
            values = bsdf.complete(example)
            floats = packed_floats(bsdf, values)
            for p in bsdf.params:
                if p.slot is None or isinstance(values.get(p.name), Texture) or p.name not in values:
                    continue
                assert np.allclose(floats[slot_floats(p.slot)], np.ravel(values[p.name]).astype(np.float32)
                                   * np.ones(len(slot_floats(p.slot))), rtol=1e-6), (name, p.name, example)


def test_pack_writes_the_declared_slots_and_no_others():
    """Rows filled with NaN: after pack, the floats that are no longer NaN are those the type
    declares (a derived slot that the table writes, a blend's rows, excepted): a slot pack()
    writes by hand without declaring it is caught, and so is a declared one it forgets."""
    from pathtrace.materials import BSDFS
    from pathtrace.device.slots import slot_floats
    for name, bsdf in BSDFS.items():
        declared = {f for n, _, _, slot, p in each_slot() if n == name and getattr(p, "packed", True)
                    for f in slot_floats(slot)}
        for example in bsdf.__class__.__dict__.get("examples", ()):
            written = set(np.flatnonzero(~np.isnan(packed_floats(bsdf, bsdf.complete(example), np.nan))).tolist())
            assert written == declared, (name, example, sorted(written ^ declared))


def test_types_read_as_others_share_their_slots():
    """A type whose rows the kernels read through another type's accessors (BSDFType.reads_as:
    a coatedconductor's base read as a roughconductor, a roughplastic as a plastic by
    kernels/coating.cl) has each of those slots where the other has it."""
    from pathtrace.materials import BSDFS
    for name, bsdf in BSDFS.items():
        for other, names in bsdf.reads_as.items():
            theirs, ours = BSDFS[other].slots(), bsdf.slots()
            for their_name, our_name in names.items():
                assert ours[our_name] == theirs[their_name], (name, our_name, other, their_name)


def test_kernels_read_material_slots_only_through_the_generated_accessors():
    """No kernel file (but those that write every type's slots alike, GENERIC) names a
    material's p0..p2 or table: each reads its parameters through <TYPE>_<NAME>(m), generated
    from the host's declarations (app/materials/registry.py: tag_source), and defines none of
    those names itself."""
    from pathtrace.materials import tag_source
    from pathtrace.lights.registry import kernel_parts
    generated = set(re.findall(r"#define (\w+)\([ml]\)", tag_source() + kernel_parts()[0][1]))
    for path in material_kernel_files() + LIGHT_FILES:
        code = code_of(path)
        raw = [m.group(0) for m in RAW_SLOT.finditer(code)]
        assert not raw, (path.name, raw)
        assert not generated & set(re.findall(r"#define\s+(\w+)", code)), path.name


def test_every_declared_slot_is_read_by_a_kernel_or_kept_for_the_host():
    """Each declared slot's accessor (or that of a type that reads its rows, reads_as) is named
    by some kernel file, or the type keeps it for the host alone (BSDFType.host_only): no slot
    lingers that nothing reads."""
    from pathtrace.materials import BSDFS
    code = " ".join(code_of(path) for path in material_kernel_files())
    named = set(re.findall(r"\b([A-Z][A-Z0-9_]*)\(", code))
    for name, bsdf, slot_name, _, _ in each_slot():
        readers = {f"{name}_{slot_name}".upper()} | {f"{other}_{their}".upper()
                                                      for other, names in bsdf.reads_as.items()
                                                      for their, ours in names.items() if ours == slot_name}
        assert readers & named or slot_name in bsdf.host_only, (name, slot_name)


# -- the LIGHT slots each delta light type declares (DeltaLight.slots), read by kernels/lights/
#    through <NAME>_LIGHT_<SLOT>(l) (app/lights/registry.py: kernel_parts) --

def example_lights():
    """(type, light) of each delta light type's examples, read as a scene file gives them."""
    from pathtrace.lights.registry import DELTA_LIGHTS
    from pathtrace.scene.toml_reader import read_scene_dict
    for name, cls in DELTA_LIGHTS.items():
        for example in cls.examples:
            scene = read_scene_dict({"camera": {"eye": [0, 2, 3], "look_at": [0, 0, 0]},
                                     "materials": {"m": {"type": "diffuse", "rho_d": 0.5}},
                                     "spheres": [{"center": [0, 0, 0], "radius": 0.5, "material": "m"}],
                                     "lights": [{"type": name, **example}]}, name)
            yield name, scene.lights[0]


def test_each_light_types_slots_are_distinct_floats_of_p0_to_p2_that_pack_writes_alone():
    """Rows filled with NaN: after pack, the floats no longer NaN are exactly those of the
    declared slots, which do not overlap; one named after a field holds its value."""
    from pathtrace.device.slots import read_slot, slot_floats
    for name, light in example_lights():
        floats = [f for s in light.slots for f in slot_floats(s.slot)]
        assert len(floats) == len(set(floats)) and max(floats) < 12, name
        rows = np.zeros(1, LIGHT)
        for field in ("p0", "p1", "p2"):
            rows[field] = np.nan
        light.pack(rows[0], {id(t): 7 for t in light.textures()})
        written = np.flatnonzero(~np.isnan(np.concatenate([rows["p0"][0], rows["p1"][0], rows["p2"][0]])))
        assert sorted(written.tolist()) == sorted(floats), name
        for s in light.slots:
            if s.name in light.fields:
                assert np.allclose(read_slot(rows[0], s.slot), getattr(light, s.name)), (name, s.name)


def test_every_light_slot_is_read_by_its_kernel():
    from pathtrace.lights.registry import DELTA_LIGHTS
    for name, cls in DELTA_LIGHTS.items():
        code = code_of(KERNELS / "lights" / f"{name}.cl")
        for s in cls.slots:
            assert re.search(rf"\b{name.upper()}_LIGHT_{s.name.upper()}\(", code), (name, s.name)


def test_combining_textures_name_their_inputs_by_the_generated_indices():
    """A combining texture's kernel reads each input by <TYPE>_INPUT_<NAME>, its index in the
    type's declaration (app/textures/registry.py: kernel_parts), never by a number, and reads
    every one of them."""
    from pathtrace.textures.registry import TEXTURES
    for name, texture in TEXTURES.items():
        code = code_of(KERNELS / "textures" / f"{name}.cl")
        assert not re.search(r"eval_input\([^,]*,[^,]*,\s*\d", code), name
        for input_name in texture.inputs:
            assert f"{name.upper()}_INPUT_{input_name.upper()}" in code, (name, input_name)


def test_the_material_flags_are_the_kernels():
    """MATERIAL.flags' bits of app/materials/bsdf.py are kernels/types.h's MATERIAL_* defines,
    each bit once."""
    from pathtrace.materials import bsdf
    defined = {name: int(value) for name, value in
               re.findall(r"#define MATERIAL_([A-Z_]+)\s+(\d+)", (KERNELS / "types.h").read_text())}
    host = {name: getattr(bsdf, name) for name in ("TWOSIDED", "DELTA", "TRANSMISSIVE", "MASKED", "NULL", "EMITS_BACK",
                                                    "PBRT_PERTURBATION")}
    assert defined == host
    assert len(set(host.values())) == len(host) and all(v & (v - 1) == 0 for v in host.values())
