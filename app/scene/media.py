"""Participating media: homogeneous media with a Henyey-Greenstein phase function, which shapes
bound (kernels/media/homogeneous.cl, kernels/phase.cl, kernels/volume.cl). A scene lists its
media; each shape may name the medium inside it and the one outside (its MediumInterface), and
the camera the one it is in.

Parameters follow both formats: pbrt-v4's sigma_a and sigma_s (per unit length, times
`scale`) and Mitsuba 3's sigma_t and albedo (sigma_s = albedo sigma_t, times `scale`); the
phase function's g, in (-1, 1) (0: isotropic)."""

from dataclasses import dataclass

import numpy as np

from pathtrace.device.types import MEDIUM
from pathtrace.parameters import Parameter

# The most media a scene may have: a primitive's two are packed into 16 bits each (kernels/types.h).
MAX_MEDIA = 0xfffe
# The largest coefficient accepted: beyond it a free flight is shorter than float32 can place
# a point along a ray in any scene.
MAX_COEFFICIENT = 1e15


@dataclass
class Medium:
    name: str
    sigma_a: np.ndarray           # (3,) absorption coefficient per unit length
    sigma_s: np.ndarray           # (3,) scattering coefficient per unit length
    g: float = 0.0                # the Henyey-Greenstein phase function's mean cosine

    # a homogeneous medium in the three formats (app/parameters.py): pbrt-v4's coefficients or
    # Mitsuba 3's (a TOML table gives either pair), both times scale; Mitsuba's g is its nested
    # <phase type="hg">'s, which its reader reads
    formats = {"mitsuba": "homogeneous", "pbrt": "homogeneous"}
    parameters = (
        Parameter("sigma_a", "color", 1.0, doc="absorption per unit length", spectrum="unbounded",
                  pbrt="sigma_a"),
        Parameter("sigma_s", "color", 1.0, doc="scattering per unit length", spectrum="unbounded",
                  pbrt="sigma_s"),
        Parameter("sigma_t", "color", optional=True, doc="extinction per unit length, instead of sigma_a "
                  "and sigma_s", mitsuba="sigma_t", mitsuba_default=1.0),
        Parameter("albedo", "color", optional=True, low=0.0, high=1.0, doc="single-scattering albedo, with "
                  "sigma_t (default 0.75)", mitsuba="albedo", mitsuba_default=0.75),
        Parameter("scale", "number", 1.0, low=0.0, doc="a factor on the coefficients", mitsuba="scale",
                  pbrt="scale"),
        Parameter("g", "number", 0.0, doc="the phase function's mean cosine, in (-1, 1)", pbrt="g"),
    )
    # what the formats' homogeneous media have and pathtrace's have not (as a light's `unsupported`)
    unsupported = {"pbrt": {"string preset": "pathtrace has no named scattering presets (it uses sigma_a and sigma_s)",
                            "Le": "pathtrace's media do not emit", "Lescale": "pathtrace's media do not emit"},
                   "mitsuba": {"has_spectral_extinction": None}}     # spectral variants' choice; pathtrace is RGB

    @classmethod
    def from_values(cls, name: str, values: dict) -> "Medium":
        """The medium of a file's values (app/parameters.py: read): sigma_t and albedo, or sigma_a
        and sigma_s, times scale. Raises ValueError naming the field with a problem."""
        scale, g = values.get("scale", 1.0), values.get("g", 0.0)
        if {"sigma_t", "albedo"} & set(values):
            if {"sigma_a", "sigma_s"} & set(values):
                raise ValueError("give either sigma_a and sigma_s, or sigma_t and albedo, not both")
            return cls.from_albedo(name, np.asarray(values.get("sigma_t", 1.0), np.float64) * scale,
                                   values.get("albedo", 0.75), g)
        return cls.checked(name, np.asarray(values.get("sigma_a", 1.0), np.float64) * scale,
                           np.asarray(values.get("sigma_s", 1.0), np.float64) * scale, g)

    @classmethod
    def from_albedo(cls, name: str, sigma_t, albedo, g: float = 0.0) -> "Medium":
        """Mitsuba 3's parameters: extinction sigma_t and single-scattering albedo. Raises
        ValueError naming the field with a problem."""
        sigma_t = _coefficient("sigma_t", sigma_t)
        albedo = _rgb("albedo", albedo)
        if np.any(albedo < 0) or np.any(albedo > 1):
            raise ValueError(f"albedo: must lie in [0, 1], got {_show(albedo)}")
        return cls.checked(name, sigma_t * (1 - albedo), sigma_t * albedo, g)

    @classmethod
    def checked(cls, name: str, sigma_a, sigma_s, g: float = 0.0) -> "Medium":
        """A medium of these coefficients, refused (ValueError naming the field) if any is
        negative, not finite or beyond MAX_COEFFICIENT, or g is outside (-1, 1)."""
        sigma_a, sigma_s = _coefficient("sigma_a", sigma_a), _coefficient("sigma_s", sigma_s)
        g = float(g)
        if not -1 < g < 1:
            raise ValueError(f"g: the phase function's mean cosine must lie in (-1, 1), got {g:g}")
        return cls(name, sigma_a, sigma_s, g)

    @property
    def sigma_t(self) -> np.ndarray:
        return self.sigma_a + self.sigma_s


def _rgb(field: str, value) -> np.ndarray:
    v = np.asarray(value, np.float64).reshape(-1)
    if v.size not in (1, 3):
        raise ValueError(f"{field}: one number or three, got {v.size}")
    v = np.broadcast_to(v, 3).copy()
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{field}: must be finite, got {_show(v)}")
    return v


def _coefficient(field: str, value) -> np.ndarray:
    v = _rgb(field, value)
    if np.any(v < 0):
        raise ValueError(f"{field}: a coefficient cannot be negative, got {_show(v)}")
    if np.any(v > MAX_COEFFICIENT):
        raise ValueError(f"{field}: beyond {MAX_COEFFICIENT:g}, got {_show(v)}")
    return v


def _show(v) -> str:
    return ", ".join(f"{x:g}" for x in np.ravel(v))


@dataclass(frozen=True)
class MediumInterface:
    """The media on the two sides of a shape (rows of the scene's media, -1: vacuum): interior
    behind its front (against its normals), exterior in front."""
    interior: int = -1
    exterior: int = -1

    def packed(self) -> int:
        """The kernels' form (kernels/types.h: prim_media)."""
        return (self.interior + 1) | ((self.exterior + 1) << 16)


NO_MEDIUM_CHANGE = -1     # kernels/types.h: a shape bounds no medium


def media_table(media: list) -> np.ndarray:
    """The MEDIUM rows of the kernels (at least one, as buffers cannot be empty)."""
    if len(media) > MAX_MEDIA:
        raise ValueError(f"{len(media)} media; pathtrace takes at most {MAX_MEDIA}")
    rows = np.zeros(max(len(media), 1), MEDIUM)
    for row, m in zip(rows, media):
        row["sigma_s"][:3], row["sigma_s"][3] = m.sigma_s, m.g
        row["sigma_t"][:3] = m.sigma_t
    return rows


def packed_interfaces(interfaces: list) -> np.ndarray:
    """Each shape's interface (a MediumInterface, or None: it bounds no medium) in the kernels'
    form, one int32 per shape."""
    return np.array([NO_MEDIUM_CHANGE if i is None else i.packed() for i in interfaces], np.int64).astype(np.int32)
