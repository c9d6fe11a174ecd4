"""Optical constants and the host's Fresnel integrals: named indices of refraction and conductor
presets as Mitsuba 3 names them (so that a scene means the same in both), and the hemispherical
Fresnel reflectance the plastic BSDF needs."""

import numpy as np

# Indices of refraction of dielectrics at 589 nm: Mitsuba 3's table of named IORs.
IOR = {
    "vacuum": 1.0, "helium": 1.00004, "hydrogen": 1.00013, "air": 1.000277,
    "carbon dioxide": 1.00045, "water": 1.333, "acetone": 1.36, "ethanol": 1.361,
    "carbon tetrachloride": 1.461, "glycerol": 1.4729, "benzene": 1.501,
    "silicone oil": 1.52045, "bromine": 1.661, "water ice": 1.31, "fused quartz": 1.458,
    "pyrex": 1.47, "acrylic glass": 1.49, "polypropylene": 1.49, "bk7": 1.5046,
    "sodium chloride": 1.544, "amber": 1.55, "pet": 1.575, "diamond": 2.419,
}

# Complex indices of refraction (eta, k) of conductors, in linear sRGB: the values Mitsuba 3.9
# derives from its spectral tables in its RGB modes (measured data, Palik et al.), so that a
# conductor named here renders as Mitsuba renders it. "none" is a perfect mirror.
CONDUCTORS = {
    "none": ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
    "a-C": ((2.944, 2.2271, 1.9682), (0.88746, 0.7993, 0.81529)),
    "Ag": ((0.15528, 0.11673, 0.13839), (4.8284, 3.1222, 2.1469)),
    "Al": ((1.6575, 0.8804, 0.52124), (9.2238, 6.2695, 4.837)),
    "Au": ((0.14304, 0.37531, 1.442), (3.983, 2.3856, 1.6034)),
    "Be": ((4.185, 3.185, 2.7841), (3.8355, 3.0101, 2.869)),
    "Cr": ((4.3697, 2.9165, 1.6549), (5.2065, 4.2313, 3.7547)),
    "Cu": ((0.20101, 0.92375, 1.1022), (3.9133, 2.453, 2.1421)),
    "Cu2O": ((3.5518, 2.9499, 2.7519), (0.11421, 0.1939, 0.60613)),
    "CuO": ((3.2475, 2.4478, 2.2102), (0.52109, 0.57003, 0.72218)),
    "Hg": ((2.3989, 1.44, 0.90957), (6.3276, 4.3719, 3.4218)),
    "HgTe": ((4.779, 3.2312, 2.6599), (1.6316, 1.5808, 1.7293)),
    "Ir": ((3.0863, 2.0822, 1.6179), (5.5922, 4.0671, 3.2673)),
    "K": ((0.064043, 0.04641, 0.038185), (2.1042, 1.3489, 0.91313)),
    "Li": ((0.26579, 0.19562, 0.22095), (3.5402, 2.3111, 1.6686)),
    "Mo": ((4.484, 3.5251, 2.7763), (4.1114, 3.4208, 3.1506)),
    "Na_palik": ((0.060269, 0.056141, 0.061988), (3.1793, 2.1125, 1.579)),
    "Nb": ((3.4201, 2.7901, 2.3956), (3.4414, 2.7377, 2.5797)),
    "Ni_palik": ((2.3673, 1.6634, 1.4671), (4.4988, 3.0502, 2.3454)),
    "Rh": ((2.5858, 1.8602, 1.5543), (6.7823, 4.703, 3.9761)),
    "Se": ((4.0583, 2.8429, 2.8209), (0.75405, 0.63844, 0.52181)),
    "Ta": ((2.0627, 2.3929, 2.6279), (2.4084, 1.7415, 1.947)),
    "Te": ((7.3902, 4.4821, 2.6371), (3.256, 3.5271, 3.2921)),
    "TiC": ((3.7005, 2.8374, 2.5823), (3.2656, 2.3516, 2.1728)),
    "TiN": ((1.6484, 1.1505, 1.3798), (3.3683, 1.9435, 1.1021)),
    "VC": ((3.6576, 2.7527, 2.5327), (3.0683, 2.1987, 1.9632)),
    "VN": ((2.8656, 2.1192, 1.9401), (3.0322, 2.0561, 1.6163)),
    "W": ((4.3708, 3.3002, 2.9984), (3.5006, 2.6049, 2.2732)),
}
# everyday names for the common metals
CONDUCTORS.update({"gold": CONDUCTORS["Au"], "silver": CONDUCTORS["Ag"],
                   "copper": CONDUCTORS["Cu"], "aluminium": CONDUCTORS["Al"],
                   "aluminum": CONDUCTORS["Al"], "chromium": CONDUCTORS["Cr"],
                   "mercury": CONDUCTORS["Hg"], "tungsten": CONDUCTORS["W"]})


def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance at a smooth interface of relative IOR eta (transmitted
    side over incident side), for |cos_i| <= 1; 1 under total internal reflection."""
    cos_i = np.abs(np.asarray(cos_i, np.float64))
    sin2_t = (1.0 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (r_s ** 2 + r_p ** 2))


def diffuse_fresnel_reflectance(eta, samples: int = 1 << 14) -> float:
    """The Fresnel reflectance averaged over a cosine-weighted hemisphere of incident directions,
    F_dr = 2 int_0^1 F(mu) mu dmu, by the midpoint rule (exact to ~1e-7 here, where Mitsuba
    uses polynomial fits good to 0.1-0.6 %)."""
    mu = (np.arange(samples) + 0.5) / samples
    return float(2.0 * np.mean(fresnel_dielectric(mu, eta) * mu))
