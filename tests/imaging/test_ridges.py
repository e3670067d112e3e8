"""Sato ridge filter: agrees with scikit-image, peaks on dark lines, zero on flat images."""

import numpy as np
import pytest

from rockmass.imaging.ridges import ridge_response, ridge_sigmas


def test_response_matches_skimage_sato_away_from_the_border():
    from skimage.filters import sato

    image = np.random.default_rng(3).random((80, 90)).astype(np.float32)  # seed 3: any texture
    sigmas = [1.0, 2.5]
    ours = ridge_response(image, sigmas, normalise=False)
    theirs = sato(image, sigmas=sigmas, black_ridges=True)
    inner = (slice(12, -12), slice(12, -12))
    np.testing.assert_allclose(ours[inner], theirs[inner], atol=1e-3 * theirs.max())


def test_constant_image_has_zero_response():
    assert not ridge_response(np.full((30, 30), 0.7), [1.0, 2.0]).any()


def test_dark_line_peaks_on_its_centre_and_bright_line_does_not_respond():
    image = np.ones((41, 41), dtype=np.float32)
    image[:, 19:22] = 0.2  # 3 px wide dark line, centre column 20
    response = ridge_response(image, ridge_sigmas(3.0))
    assert np.all(response[5:-5].argmax(axis=1) == 20)
    bright = 1.2 - image
    assert ridge_response(bright, ridge_sigmas(3.0))[:, 20].max() == 0.0


def test_normalised_response_is_independent_of_contrast():
    image = np.ones((41, 41), dtype=np.float32)
    image[:, 20] = 0.5
    a = ridge_response(image, [1.0, 1.5])
    b = ridge_response(0.1 * image, [1.0, 1.5])
    np.testing.assert_allclose(a, b, atol=1e-5)


def test_sigmas_centre_on_half_the_width_and_respect_the_floor():
    np.testing.assert_allclose(ridge_sigmas(6.0, 3, spread=4.0), [1.5, 3.0, 6.0])
    assert ridge_sigmas(1.0, 3).min() == 1.0
    with pytest.raises(ValueError, match="joint_width_px"):
        ridge_sigmas(0.0)


def test_input_not_modified():
    image = np.random.default_rng(4).random((20, 20))
    before = image.copy()
    ridge_response(image, [1.0])
    np.testing.assert_array_equal(image, before)


@pytest.mark.parametrize("sigma", [1.0, 6.0])
def test_cutting_the_kernel_tails_changes_nothing_float32_resolves(sigma, monkeypatch):
    """The Hessian's kernels lose their ends under 1e-8 of their peak: against the full kernels
    (radius about 11 sigma) the response differs by less than float32's relative resolution."""
    from rockmass.imaging import ridges

    image = np.random.default_rng(4).random((160, 170)).astype(np.float32)
    cut = ridge_response(image, [sigma], normalise=False)
    monkeypatch.setattr(ridges, "_KERNEL_TAIL", 0.0)
    full = ridge_response(image, [sigma], normalise=False)
    assert len(ridges._gaussian_kernels(sigma)[0]) > 1.6 * (12 * sigma)  # the full ones: wide
    np.testing.assert_allclose(cut, full, rtol=0, atol=2e-6 * float(full.max()))
    monkeypatch.undo()
    assert len(ridges._gaussian_kernels(sigma)[0]) <= 2 * 6.6 * sigma + 1  # the cut ones
