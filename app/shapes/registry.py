"""The registry of analytic shape kinds: every ShapeKind of a module of this package, its tag,
and the kernels' dispatch over the kinds (shape_intersect, shape_uv, shape_point, shape_area,
shape_sample), as app/materials/registry.py generates the BSDFs'. Adding a kind takes its
kernel file (kernels/shapes/<kind>.cl, the functions intersect_<kind>, <kind>_uv, <kind>_point,
<kind>_area and sample_<kind>) and its host module here: registered by being in the package,
it is tested by tests/test_shapes.py. Tag 0 is the triangle (kernels/shapes/analytic.cl)."""

import importlib
import pkgutil
from pathlib import Path

from pathtrace.shapes.shape import ShapeKind


def _kinds() -> dict:
    kinds = {}
    for module in sorted(m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)])):
        if module in ("registry", "shape"):
            continue
        for value in vars(importlib.import_module(f"pathtrace.shapes.{module}")).values():
            if isinstance(value, type) and issubclass(value, ShapeKind) and value.name:     # not a base
                kinds[value.name] = value()
    return kinds


SHAPES = _kinds()
TAGS = {name: i + 1 for i, name in enumerate(SHAPES)}


def kernel_files(names) -> list[str]:
    """The kernel files of the kinds `names`, then the world-space layer over them."""
    return [f"shapes/{n}.cl" for n in SHAPES if n in names]


def dispatch_source(names) -> str:
    """The SHAPE_<KIND> tags and the dispatch over the kinds `names` (kernels/shapes/analytic.cl)."""
    kinds = [n for n in SHAPES if n in names]
    tags = "".join(f"#define SHAPE_{n.upper()} {TAGS[n]}\n" for n in kinds)

    def switch(call, default, returns=True):
        ret = "return " if returns else ""
        end = "" if returns else " return;"
        cases = "".join(f"    case SHAPE_{n.upper()}: {ret}{call.format(n)};{end}\n" for n in kinds)
        return f"{{\n    switch (kind) {{\n{cases}    default: {default}\n    }}\n}}\n"
    rows = "int kind, const global float4 *f"
    return (tags
            + f"float shape_intersect({rows}, float3 o, float3 d, float t_max, float2 *uv)\n"
            + switch("intersect_{}(f, o, d, t_max, uv)", "return INFINITY;")
            + f"float2 shape_uv({rows}, float3 p)\n" + switch("{}_uv(f, p)", "return (float2)(0.0f);")
            + f"void shape_point({rows}, float2 uv, float3 *p, float3 *error, float3 *n, float3 *dpdu, float3 *dpdv)\n"
            + switch("{}_point(f, uv, p, error, n, dpdu, dpdv)", "*p = *error = *n = *dpdu = *dpdv = (float3)(0.0f);",
                     returns=False)
            + f"float shape_area({rows})\n" + switch("{}_area(f)", "return 1.0f;")
            + f"float2 shape_sample({rows}, float2 u)\n" + switch("sample_{}(f, u)", "return (float2)(0.0f);"))
