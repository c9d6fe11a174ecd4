"""app/io/tonecurve.py against closed forms: the sRGB transfer function's defining points, exposure
as a power of two, Narkowicz's ACES fit, and 8-bit rounding. tests/test_viewer.py checks that
shaders/display.frag draws the same values."""

import numpy as np
import pytest

from pathtrace.io.tonecurve import aces_fit, linear_to_srgb, tonemap, to_8bit


def test_srgb_transfer_function_at_its_defining_points():
    # IEC 61966-2-1: linear below 0.0031308 (slope 12.92), 1.055 x^(1/2.4) - 0.055 above; both
    # pieces meet at 0.04045; 0 and 1 are fixed; values outside [0, 1] clip
    x = np.array([-1.0, 0.0, 0.001, 0.0031308, 0.18, 0.5, 1.0, 4.0])
    expected = [0.0, 0.0, 0.01292, 0.04045, 1.055 * 0.18 ** (1 / 2.4) - 0.055,
                1.055 * 0.5 ** (1 / 2.4) - 0.055, 1.0, 1.0]
    np.testing.assert_allclose(linear_to_srgb(x), expected, atol=2e-6)


def test_exposure_is_a_power_of_two():
    x = np.array([[[0.01, 0.02, 0.04]]])
    np.testing.assert_allclose(tonemap(x, exposure=1), linear_to_srgb(2 * x))
    np.testing.assert_allclose(tonemap(x, exposure=-2), linear_to_srgb(x / 4))


def test_aces_fit_values_and_shape():
    # (x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14) at 0, 1 and large x
    assert aces_fit(np.array(0.0)) == 0.0
    assert aces_fit(np.array(1.0)) == pytest.approx(2.54 / 3.16)
    assert aces_fit(np.array(1e6)) == 1.0
    x = np.linspace(0, 20, 1000)
    assert np.all(np.diff(aces_fit(x)) >= 0)


def test_8bit_rounds_to_nearest_and_clips():
    np.testing.assert_array_equal(to_8bit(np.array([-0.1, 0.0, 0.6 / 255, 0.4 / 255, 0.5, 1.0, 1.5])),
                                  [0, 0, 1, 0, 128, 255, 255])
