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
