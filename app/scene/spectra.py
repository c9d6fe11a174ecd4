"""Spectra as an RGB renderer sees them: blackbodies, sampled spectra and pbrt-v4's named spectra
converted to linear sRGB, as pbrt-v4's RGB film would record them.

An emission spectrum becomes the colour of its light at a luminance of 1 (pbrt-v4 divides a
light's `scale` by the spectrum's photometric value, so that a light's spectrum sets only its
colour); a reflectance or an index of refraction becomes the colour it has under a white light.
The colour matching functions are Wyman, Sloan and Shirley's multi-lobe fit of CIE 1931 ("Simple
Analytic Approximations to the CIE XYZ Color Matching Functions", JCGT 2013), within 1 % of the
tables where they matter."""

import numpy as np

from pathtrace.materials.optics import CONDUCTORS

WAVELENGTHS = np.arange(360.0, 831.0, 1.0)        # nm: pbrt-v4's visible range
# CIE XYZ to linear sRGB (D65 white)
XYZ_TO_RGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                       [-0.9692660, 1.8760108, 0.0415560],
                       [0.0556434, -0.2040259, 1.0572252]])
D65_TEMPERATURE = 6504.0       # the correlated colour temperature of CIE D65, white's stand-in


def _lobe(wl, mu, s1, s2):
    s = np.where(wl < mu, s1, s2)
    return np.exp(-0.5 * ((wl - mu) / s) ** 2)


def cmf(wl: np.ndarray) -> np.ndarray:
    """The CIE 1931 colour matching functions at wavelengths wl (nm): (len(wl), 3)."""
    x = 1.056 * _lobe(wl, 599.8, 37.9, 31.0) + 0.362 * _lobe(wl, 442.0, 16.0, 26.7) \
        - 0.065 * _lobe(wl, 501.1, 20.4, 26.2)
    y = 0.821 * _lobe(wl, 568.8, 46.9, 40.5) + 0.286 * _lobe(wl, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(wl, 437.0, 11.8, 36.0) + 0.681 * _lobe(wl, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


def blackbody(wl: np.ndarray, kelvin: float) -> np.ndarray:
    """Planck's law: the spectral radiance of a blackbody at wavelengths wl (nm), unscaled."""
    h, c, k = 6.62606957e-34, 299792458.0, 1.3806488e-23
    m = wl * 1e-9
    with np.errstate(over="ignore"):        # a cold body: expm1 overflows to inf, the radiance to 0
        return 2 * h * c * c / (m ** 5 * np.expm1(h * c / (m * k * kelvin)))


def emission_rgb(values: np.ndarray) -> np.ndarray:
    """The linear sRGB of an emission spectrum sampled at WAVELENGTHS, at luminance 1. Raises
    ValueError for one of no visible light (a zero spectrum, a blackbody of a few kelvin), which
    has no colour at luminance 1 (pbrt-v4 divides by its zero photometric value)."""
    xyz = values @ cmf(WAVELENGTHS)
    if not xyz[1] > 0 or not np.all(np.isfinite(xyz)):
        raise ValueError("emits no visible light (a luminance of 0), so it has no colour to scale")
    return XYZ_TO_RGB @ (xyz / xyz[1])


def blackbody_rgb(kelvin: float) -> np.ndarray:
    """A blackbody's colour at luminance 1 (pbrt-v4's "blackbody L" [kelvin])."""
    return emission_rgb(blackbody(WAVELENGTHS, kelvin))


def reflectance_rgb(values: np.ndarray) -> np.ndarray:
    """The linear sRGB of a reflectance (or any unitless) spectrum sampled at WAVELENGTHS: its
    colour under a D65-like white, scaled so that a constant spectrum keeps its value."""
    white = blackbody(WAVELENGTHS, D65_TEMPERATURE)
    weights = cmf(WAVELENGTHS) * white[:, None]
    rgb_of = lambda s: XYZ_TO_RGB @ (s @ weights)          # noqa: E731
    return rgb_of(values) / rgb_of(np.ones_like(values))


def sampled(pairs: np.ndarray) -> np.ndarray:
    """A spectrum given as (wavelength, value) pairs, piecewise linear, at WAVELENGTHS (held
    constant beyond the first and last pair, as pbrt-v4's PiecewiseLinearSpectrum is not:
    there it is 0, which only matters for spectra that stop inside the visible range)."""
    wl, v = pairs[0::2], pairs[1::2]
    if len(wl) < 1 or np.any(np.diff(wl) <= 0):
        raise ValueError("wavelengths must increase")
    return np.interp(WAVELENGTHS, wl, v)


# pbrt-v4's named spectra that scenes use, as RGB. Conductors: the RGB complex IORs that
# app/materials/optics.py holds for Mitsuba's measured data of the same metal (pbrt-v4's tables
# come from the same measurements). CuZn (brass) has no such entry and takes copper's; MgO and
# TiO2, dielectrics, their refractive indices at 589 nm with k = 0. Glasses: Schott's n_d (587.6
# nm); pbrt-v4 renders their dispersion, an RGB renderer their mean.
_METALS = {"Ag": "Ag", "Al": "Al", "Au": "Au", "Cu": "Cu", "CuZn": "Cu"}
_DIELECTRIC_METALS = {"MgO": 1.7355, "TiO2": 2.6142}
GLASSES = {"glass-BK7": 1.5168, "glass-BAF10": 1.6700, "glass-FK51A": 1.4866, "glass-LASF9": 1.8503,
           "glass-F5": 1.6034, "glass-F10": 1.7283, "glass-F11": 1.7847}
ILLUMINANTS = {"stdillum-D65": D65_TEMPERATURE, "stdillum-D50": 5003.0, "stdillum-A": 2856.0,
               "illum-acesD60": 6000.0}


def named_spectrum(name: str):
    """(rgb, note): a named spectrum's RGB, and what it approximates ("" where nothing); raises
    KeyError for a name pbrt-v4 does not have or pathtrace does not know."""
    if name.startswith("metal-") and name.endswith(("-eta", "-k")):
        metal, part = name[6:].rsplit("-", 1)
        if metal in _DIELECTRIC_METALS:
            return np.full(3, _DIELECTRIC_METALS[metal] if part == "eta" else 0.0), ""
        if metal in _METALS:
            eta, k = CONDUCTORS[_METALS[metal]]
            note = "copper's (pathtrace has no brass data)" if metal == "CuZn" else ""
            return np.array(eta if part == "eta" else k, np.float64), note
    if name in GLASSES:
        return np.full(3, GLASSES[name]), "its index at 587.6 nm (no dispersion)"
    if name in ILLUMINANTS:
        rgb = blackbody_rgb(ILLUMINANTS[name]) if name != "stdillum-D65" else np.ones(3)
        note = "" if name == "stdillum-D65" else f"a blackbody of {ILLUMINANTS[name]:g} K"
        return rgb, note
    raise KeyError(name)
