"""The NumPy dtypes of app/types.py match the device's layout of kernels/types.h."""

import numpy as np

from app.types import BVH_NODE, MATERIAL, RENDER_PARAMS

SOURCE = """
#define OFF(T, f) (int)__builtin_offsetof(T, f)
kernel void layout(global int *out)
{
    out[0] = sizeof(Material); out[1] = OFF(Material, specular); out[2] = OFF(Material, emission);
    out[3] = sizeof(BVHNode); out[4] = OFF(BVHNode, child[1]); out[5] = OFF(BVHChild, index);
    out[6] = OFF(BVHChild, hi); out[7] = OFF(BVHChild, count);
    out[8] = sizeof(RenderParams); out[9] = OFF(RenderParams, width);
    out[10] = OFF(RenderParams, seed); out[11] = OFF(RenderParams, env_rotation);
    out[12] = sizeof(Sphere);
}
"""


def test_dtypes_match_device_layout(kernels):
    out = np.zeros(13, np.int32)
    kernels(SOURCE)("layout", 1, out)
    child = BVH_NODE["child"].base
    expected = [
        MATERIAL.itemsize, MATERIAL.fields["specular"][1], MATERIAL.fields["emission"][1],
        BVH_NODE.itemsize, child.itemsize, child.fields["index"][1],
        child.fields["hi"][1], child.fields["count"][1],
        RENDER_PARAMS.itemsize, RENDER_PARAMS.fields["width"][1],
        RENDER_PARAMS.fields["seed"][1], RENDER_PARAMS.fields["env_rotation"][1], 16,
    ]
    assert out.tolist() == expected
