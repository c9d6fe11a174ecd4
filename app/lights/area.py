"""Area lights: shapes that emit (a material's emission, app/materials), and pbrt-v4's `diffuse`
AreaLightSource's radiance for them, which its `power` makes depend on the shape's area."""

import math

import numpy as np

from pathtrace.lights.light import MAX_RADIANCE
from pathtrace.parameters import Parameter

# the most material rows one `power` area light's triangles take (pbrt_radiance)
MAX_POWER_ROWS = 256


class DiffuseAreaLight:
    """pbrt-v4's diffuse AreaLightSource, its parameters pbrt-v4's own (app/parameters.py), which
    pbrt_radiance makes the emission of the shapes under it."""
    formats = {"pbrt": "diffuse"}
    parameters = (
        Parameter(None, "color", spectrum="illuminant", pbrt="L", pbrt_default=(1.0, 1.0, 1.0), doc="its radiance"),
        Parameter(None, "number", pbrt="scale", pbrt_default=1.0, doc="a factor on L"),
        Parameter(None, "bool", pbrt="twosided", pbrt_default=False, doc="whether it emits from both sides"),
        Parameter(None, "number", pbrt="power", pbrt_default=-1.0, doc="where positive, the power each shape emits"))
    unsupported = {"pbrt": {"string filename": "pathtrace's area lights have no image (they emit L)"}}


def pbrt_radiance(given: dict, vertices, faces, area, warn) -> list:
    """The emitted radiance of a shape under pbrt-v4's diffuse AreaLightSource of the values
    `given` by its declared names (DiffuseAreaLight: L as rgb, scale, twosided and power, none
    where not positive), as [(faces, radiance)] (faces an index array of the mesh's, or None for
    all); `area`: an analytic shape's (None for a mesh). Raises ValueError("<pbrt name>: <problem>").

    `power` is applied as pbrt-v4 applies it: a mesh is one DiffuseAreaLight per triangle
    (src/pbrt/scene.cpp, the area lights' loop over the shapes Shape::Create returns), and
    DiffuseAreaLight::Create (src/pbrt/lights.cpp) scales L by power / k_e with
    k_e = (twosided ? 2 : 1) * shape.Area() * Pi, the area being the triangle's own (in the
    world) and an analytic shape's in its object's space (pbrt-v4's Sphere, Disk and
    Cylinder::Area, src/pbrt/shapes.h, ignore the transform). An RGB L keeps its magnitude
    (scale /= SpectrumToPhotometric(L) sees only the colour space's illuminant), so L is not
    divided by its luminance. Triangles of one area share a radiance, and a material row."""
    scale, twosided, power = given["scale"], given["twosided"], given["power"]
    le = np.asarray(given["L"], np.float64) * scale
    if np.any(le < 0):
        raise ValueError(f"{'scale' if scale < 0 else 'L'}: an emitted radiance must not be negative")
    if power <= 0:
        parts, cause = [(None, le)], "'L' times 'scale'"
    else:
        parts, area = _powered(le, power, math.pi * (2 if twosided else 1), vertices, faces, area, warn)
        cause = f"'power' {power:g} over the shape's area of {area:.3g}" + \
            ("" if faces is None else " (its smallest triangle's: each triangle emits the power, as pbrt-v4's do)")
    top = max(float(np.max(e)) for _, e in parts)
    if not top <= MAX_RADIANCE:
        raise ValueError(f"{cause} gives an emitted radiance of {top:.3g}, "
                         f"beyond {MAX_RADIANCE:g}, where the sums of samples overflow")
    return parts


def _powered(le, power, k_e, vertices, faces, area, warn) -> tuple:
    """pbrt_radiance's [(faces, radiance)] of a light given `power`, L power / (k_e area) with
    each triangle's own area (an analytic shape's `area`), and the least area."""
    if area is not None:
        return [(None, le * power / (k_e * area))], area
    p = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    # areas equal in float32 (a quad's two halves, but for rounding) share a row, at their mean
    _, group = np.unique(area.astype(np.float32), return_inverse=True)
    areas = np.bincount(group, weights=area) / np.bincount(group)
    if len(areas) > MAX_POWER_ROWS:
        # a row per triangle would outgrow the material table: areas in MAX_POWER_ROWS
        # bins of equal ratio, each triangle given its bin's geometric mean
        edges = np.geomspace(areas[0], areas[-1], MAX_POWER_ROWS + 1)
        bins = np.clip(np.searchsorted(edges, areas, side="right") - 1, 0, MAX_POWER_ROWS - 1)
        spread = float(edges[1] / edges[0]) ** 0.5 - 1
        warn(f"'power' over {len(areas)} triangle areas; pathtrace gives each triangle the "
             f"radiance of one of {MAX_POWER_ROWS} area classes, within {spread:.1%} of pbrt-v4's")
        areas, group = np.sqrt(edges[:-1] * edges[1:]), bins[group]
    return [(np.flatnonzero(group == g), le * power / (k_e * float(a)))
            for g, a in enumerate(areas) if np.any(group == g)], float(area.min())
