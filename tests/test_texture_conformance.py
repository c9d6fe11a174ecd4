"""Every registered texture type, through the examples it declares (TextureType.examples): the
kernel's values over the unit square of uv against the host's mean (the constant that stands for
the texture in the material table, emitted power and lobe choices) and bounds (the readers'
range checks). A new type is tested by being registered."""

import numpy as np
import pytest

from pathtrace.textures import TEXTURES, Texture
from tests.test_textures import lookup

GRID = 192        # uv midpoints per side: a multiple of every example's period (checks, texels)
EXAMPLES = [(f"{name}-{k}", name, params) for name, kind in TEXTURES.items() for k, params in enumerate(kind.examples)]


def built(name, params):
    """The example's Texture, its inputs that are textures completed too."""
    values = {k: built(v.type, v.params) if isinstance(v, Texture) else v for k, v in params.items()}
    return Texture(name, TEXTURES[name].complete(values))


def test_every_registered_type_declares_examples():
    for name, kind in TEXTURES.items():
        assert type(kind).__dict__.get("examples"), f"{name} declares no examples"


@pytest.mark.parametrize("key,name,params", EXAMPLES, ids=[key for key, _, _ in EXAMPLES])
def test_the_kernels_values_have_the_hosts_mean_and_lie_in_its_bounds(kernels, key, name, params):
    """The mean of the kernel's values at the midpoints of a grid over [0, 1)^2 is the host's mean
    (the grid is exact for the examples' piecewise constant and bilinear periodic values, up to
    float32), every value lies within the host's bounds, and the values are not all one (but for
    a constant) so that the mean says something."""
    tex = built(name, params)
    t = (np.arange(GRID) + 0.5) / GRID
    uv = np.stack(np.meshgrid(t, t, indexing="ij"), -1).reshape(-1, 2)
    values = lookup(kernels, tex, uv).astype(np.float64)
    low, high = (np.asarray(b, np.float64) for b in TEXTURES[name].bounds(tex))
    np.testing.assert_allclose(values.mean(axis=0), tex.mean(), rtol=1e-5, atol=1e-6)
    slack = 1e-6 * np.maximum(np.abs(low), np.abs(high)) + 1e-7
    assert np.all(values >= low - slack) and np.all(values <= high + slack), (values.min(0), values.max(0), low, high)
    assert name == "constant" or np.ptp(values, axis=0).max() > 0
