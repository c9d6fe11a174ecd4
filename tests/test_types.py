"""The NumPy dtypes of app/device/types.py match the device's layout of kernels/types.h, field by field
(so that swapped fields of equal size are caught too)."""

import numpy as np
import pytest

from pathtrace.device.types import (BVH_NODE, INSTANCE, LIGHT, LIGHT_NODE, MATERIAL, MEDIUM, PATH_RECORD, RENDER_PARAMS,
                             TEXTURE, TEXTURE_BINDING, TRIANGLE)

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


# -- the MATERIAL slots each material type declares (Param.slot), whose accessors the kernels
#    read (app/materials/registry.py: tag_source) --

def slot_components(slot: str) -> list:
    """'p1.xyz' -> [4, 5, 6]: the floats of p0..p2 (12 in all) it names."""
    field, components = slot.split(".")
    return [4 * int(field[1]) + "xyzw".index(c) for c in components]


def test_each_material_types_slots_are_distinct_floats_of_its_kind():
    from pathtrace.materials import BSDFS
    for name, bsdf in BSDFS.items():
        taken = []
        for p in bsdf.params:
            if p.slot is None:
                continue
            floats = slot_components(p.slot)
            assert len(floats) == (3 if p.kind == "color" else 1), (name, p.name, p.slot)
            assert all(0 <= f < 12 for f in floats) and not set(floats) & set(taken), (name, p.name, p.slot)
            taken += floats


def test_pack_writes_each_slotted_parameter_where_its_slot_says():
    """A texture's value is written into the slot at each hit (kernels/shading.cl), so pack must
    put the constant there too, as it is: the slot is the parameter's one place."""
    from pathtrace.materials import BSDFS
    from pathtrace.textures.texture import Texture
    for name, bsdf in BSDFS.items():
        for example in bsdf.__class__.__dict__.get("examples", ()):
            values = bsdf.complete(example)
            rows = np.zeros(1, MATERIAL)
            bsdf.pack({k: (v if isinstance(v, (str, Texture)) else np.atleast_2d(v) if np.ndim(v) else np.atleast_1d(v))
                       for k, v in values.items()}, rows)
            floats = np.concatenate([rows["p0"][0], rows["p1"][0], rows["p2"][0]])
            for p in bsdf.params:
                if p.slot is None or isinstance(values.get(p.name), Texture) or p.name not in values:
                    continue
                assert np.allclose(floats[slot_components(p.slot)], np.ravel(values[p.name]).astype(np.float32)
                                   * np.ones(len(slot_components(p.slot))), rtol=1e-6), (name, p.name, example)
