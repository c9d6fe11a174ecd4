"""Statistical image comparison in the manner of Mitsuba 3's render tests: a per-pixel Z-test of
a mean image against a reference, with the Sidak correction for the number of pixels."""

import numpy as np
from scipy import stats


def block_mean(image, block):
    h, w = image.shape[0] // block * block, image.shape[1] // block * block
    return image[:h, :w].reshape(h // block, block, w // block, block, -1).mean(axis=(1, 3))


def z_test(mean, var_of_mean, ref, ref_var_of_mean=0.0, alpha=0.001, block=1, rel_floor=1e-5):
    """Tests that `mean` and `ref` have the same expectation, pixel by pixel, given each one's
    variance of the mean. `alpha` is the chance that a test of two images of one expectation
    fails: the suite holds about 250 such tests, whose samples any change to a kernel's use of
    random numbers draws anew (the generic program's, say), so at 0.01 two or three of them
    would fail by chance after each such change (three did on 2026-11-28; each passed again
    with 8x the samples); at 0.001 one in four changes costs a look. Pixels are first averaged over block x block tiles (which makes the
    sums closer to normal). A standard deviation floor of rel_floor * |ref| covers float32
    rounding where the variance is zero (a sky seen directly). The whole image's mean per channel
    is tested beside the blocks: a bias spread over the image, which each block's noise hides, is
    sqrt(blocks) times plainer there, so a test at a given spp detects a global bias
    sqrt(blocks) times smaller than its blocks can. Returns (passed, smallest
    p-value, Sidak-corrected threshold)."""
    variance = variance_of_means(var_of_mean, block) \
        + variance_of_means(np.broadcast_to(ref_var_of_mean, mean.shape), block)
    return z_test_of(blocks_and_image(mean, block), variance, blocks_and_image(ref, block), alpha, rel_floor)


def blocks_and_image(images, block):
    """The means of (..., H, W, C) images' block x block-pixel blocks (the rows and columns beyond
    a whole block left out), then the whole image's, the blocks' mean: (..., blocks + 1, C)."""
    h, w = images.shape[-3] // block, images.shape[-2] // block
    blocks = images[..., :h * block, :w * block, :].reshape(*images.shape[:-3], h, block, w, block, images.shape[-1])
    blocks = blocks.mean(axis=(-4, -2)).reshape(*images.shape[:-3], h * w, images.shape[-1])
    return np.concatenate([blocks, blocks.mean(axis=-2, keepdims=True)], axis=-2)


def variance_of_means(variance, block):
    """The variances of blocks_and_image's means from their pixels' (H, W, C) variances, the
    pixels taken as independent: a mean's is its pixels' mean variance over their count."""
    means = blocks_and_image(variance, block)
    counts = np.array([block * block] * (means.shape[0] - 1) + [block * block * (means.shape[0] - 1)])
    return means / counts[:, None]


def z_test_of(mean, variance, ref, alpha=0.001, rel_floor=1e-5):
    """z_test's test of values (blocks' means, an image's) against `ref`, given the variance of
    their differences, with the Sidak correction for their count."""
    z = (mean - ref) / np.sqrt(variance + (rel_floor * np.abs(ref)) ** 2 + 1e-30)
    p = 2 * stats.norm.sf(np.abs(z))
    threshold = 1 - (1 - alpha) ** (1 / p.size)
    return bool(p.min() >= threshold), float(p.min()), threshold
