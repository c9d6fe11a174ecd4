"""A shape's texture coordinates: the affine map (s, t) = A (u, v) + b from its kind's parameters
(u, v) (kernels/shapes/<kind>.cl) to the (s, t) its textures are looked up at. A format's shape
whose texture coordinates no transform of the kind gives takes one of these: Mitsuba 3's disk
(r, phi / 2 pi), and pbrt-v4's disk, whose image lookup at (u, 1 - v) no mirror of the plane
turns to (u, v). A shape's mode goes to the kernels as its index in row 7's y of its rows
(app/shapes/shape.py); texture_uv_source generates the kernels' maps from A and b, so the
modes are defined here alone."""

from enum import Enum

import numpy as np


class TextureUV(Enum):
    """A mode, by the TOML value that names it ([[shapes]] texture_uv), with its matrix A and
    offset b. The first is the default."""
    # the kind's own (u, v)
    KIND = ("u,v", ((1, 0), (0, 1)), (0, 0))
    # Mitsuba 3's disk: the unit disk's (1 - v, u) = (r, phi / 2 pi) (src/shapes/disk.cpp)
    MITSUBA_DISK = ("1-v,u", ((0, -1), (1, 0)), (1, 0))
    # pbrt-v4's: its images are looked up at (u, 1 - v) (src/pbrt/textures.cpp,
    # SpectrumImageTexture::Evaluate), pathtrace's at (u, v), v = 0 an image's top row
    PBRT = ("u,1-v", ((1, 0), (0, -1)), (0, 1))

    def __new__(cls, formula, matrix, offset):
        mode = object.__new__(cls)
        mode._value_ = formula
        mode.matrix, mode.offset = np.array(matrix, np.float64), np.array(offset, np.float64)
        return mode

    @property
    def index(self) -> int:
        """Its value in the shape's rows."""
        return list(TextureUV).index(self)


def _sum(terms, constant=0.0) -> str:
    """C text of constant + the sum of c * name over the (c, name) of `terms`, leaving out zeros."""
    text = f"{float(constant)!r}f" if constant else ""
    for c, name in terms:
        if c == 0:
            continue
        term = name if abs(c) == 1 else f"{float(abs(c))!r}f * {name}"
        text = f"{text} {'-' if c < 0 else '+'} {term}" if text else f"{'-' if c < 0 else ''}{term}"
    return text or "0.0f"


def texture_uv_source() -> str:
    """The kernels' texture_uv_map(mode, uv), the texture coordinates (s, t) of a shape's (u, v),
    and texture_uv_derivatives(mode, dp/du, dp/dv, &dp/ds, &dp/dt): the chain rule
    [dp/ds dp/dt] = [dp/du dp/dv] A^-1, so that the frame's tangents run along the texture's
    axes. The first mode is the default case."""
    modes = list(TextureUV)
    uv, derivatives = [], []
    for mode in modes[1:] + modes[:1]:
        label = f"case {mode.index}:" if mode.index else "default:"
        a, b = mode.matrix, mode.offset
        s, t = (_sum(zip(a[i], ("uv.x", "uv.y")), b[i]) for i in range(2))
        uv.append(f"    {label} return (float2)({s}, {t});\n")
        inverse = np.linalg.inv(a)
        ds, dt = (_sum(zip(inverse[:, j], ("dpdu", "dpdv"))) for j in range(2))
        derivatives.append(f"    {label} *dpds = {ds}; *dpdt = {dt}; return;\n")
    return ("float2 texture_uv_map(int mode, float2 uv)\n{\n    switch (mode) {\n" + "".join(uv) + "    }\n}\n"
            + "void texture_uv_derivatives(int mode, float3 dpdu, float3 dpdv, float3 *dpds, float3 *dpdt)\n{\n"
            + "    switch (mode) {\n" + "".join(derivatives) + "    }\n}\n")
