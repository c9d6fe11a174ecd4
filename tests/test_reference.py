"""Images against references from an independent renderer, Mitsuba 3 (scripts/make_references.py
regenerates them), with a per-pixel Z-test as Mitsuba's own render tests do."""

from pathlib import Path

import numpy as np
import pytest

from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene
from tests.stats import z_test

# What a render converges with is the scene's own program, which replaces the generic one once
# built (pathtrace.device.programs); tests/test_programs.py compares the two on every test scene.
pytestmark = pytest.mark.specialised

REFERENCES = sorted((Path(__file__).parent / "references").glob("*.npz"))
XML_SCENES = Path(__file__).parent / "scenes"    # Mitsuba XML, read by app/scene/mitsuba.py


def reference_scene(name):
    """A reference's scene: the Mitsuba XML file Mitsuba rendered, else a built-in scene."""
    xml = XML_SCENES / f"{name}.xml"
    return load_scene(str(xml) if xml.exists() else name)


def test_references_are_present():
    assert {p.stem for p in REFERENCES} >= {"simple-diffuse", "spheres8k-diffuse", "cbox", "envmap-spheres", "meshes",
                                            "meshes-smaller", "meshes-larger", "textures", "masks", "normal-maps",
                                            "lights", "thinlens", "beckmann", "roughdielectric", "roughplastic", "metals", "media-sphere", "media-glass",
                                            "media-fog", "anisotropic", "blend", "equal-area", "principled", "instances",
                                            "glass-mesh", "open-sheet", "serialized"} | NO_NEE


# Scenes lit by delta lights (point, spot, directional), "lights" and "media-fog", are compared
# with NEE only: no path can hit such a light, so without NEE they are dark, in pathtrace as in
# Mitsuba's estimators without emitter sampling (test_lights.py checks that they are).
# Without NEE, once per kind of emitter and medium and for the delta BSDFs, which NEE does not
# reach: a small lamp, an area light, glass and metals, media. Each BSDF is compared without NEE
# and with it by tests/test_nee.py (the materials showcase, every BSDF type), and with NEE against
# Mitsuba here. (Without NEE a case needs 4096 samples per pixel: at 2048 the blocks of
# anisotropic.xml that the light reaches only through a glossy bounce fell short, 11 of 540
# beyond 3 standard errors, the rare bright paths not yet drawn.)
NO_NEE = {"simple-diffuse", "cbox", "material-spheres", "media-sphere", "media-glass"}
# Mitsuba's own bias, relative to the mean, where it is known: its blendbsdf weighs emitter hits
# by the chosen component's density and light samples by the mixture's (docs/mitsuba.md), which
# moved blocks of tests/scenes/blend.xml by up to 1.6 % against pathtrace's unbiased mixture
# (whose white-and-mirror blend passes the white furnace, test_materials.py)
# And where both render the same map but interpolate its texels differently: the sky of
# equal-area.xml, seen directly (zero variance), came out up to 0.3 % apart at its glow.
REFERENCE_BIAS = {"blend": 0.02, "equal-area": 0.005}
# Lit by the shipped map's sun, with mirror and glass spheres: with NEE at 2048 samples per pixel
# a block failed (p 2.2e-6 against the threshold 1.55e-5), its sample variance short of the rare
# sun-through-mirror paths'
SUN_THROUGH_DELTAS = {"material-spheres-hdr"}
CASES = [(path, nee) for path in REFERENCES for nee in (True, False) if nee or path.stem in NO_NEE]


@pytest.mark.parametrize("path,nee", CASES, ids=lambda c: c.stem if isinstance(c, Path) else ("nee" if c else "no-nee"))
def test_matches_mitsuba(backend, path, nee):
    ref = np.load(path)
    h, w, _ = ref["mean"].shape
    scene = reference_scene(path.stem).with_settings(max_depth=int(ref["max_depth"]), russian_roulette="off", nee=nee)
    r = Renderer(backend, scene, w, h)
    # Without NEE we hit the lights by chance: far from the lamp of `simple` a pixel meets it
    # about once in a thousand samples, and a sample variance that has not seen it is too
    # small. 4096 samples per pixel, pooled over 4x4 blocks, see it dozens of times. With NEE
    # every sample sees the lights and 1024 do; but not where the light is a map's sun, which
    # the paths through delta BSDFs meet by chance alone (4096). The image's mean, tested beside
    # the blocks (tests/stats.py), holds a bias spread over the image to about a tenth of a
    # block's noise.
    for _ in range(8 if nee and path.stem not in SUN_THROUGH_DELTAS else 32):
        r.add_samples(128)
    r.finish()
    assert r.dropped_samples() == 0     # a NaN dropped would show as a bias, not as what it is
    ok, p, threshold = z_test(r.mean(), r.variance() / r.samples, ref["mean"], ref["var_of_mean"], block=4,
                              rel_floor=REFERENCE_BIAS.get(path.stem, 1e-5))
    assert ok, f"smallest p-value {p:.3g} below the Sidak threshold {threshold:.3g}"
