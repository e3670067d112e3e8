"""Robust hysteresis thresholds, the region-of-interest mask and small-object removal."""

import numpy as np
import pytest

from rockmass.imaging.segment import (fill_holes, remove_small_objects, robust_thresholds, roi_mask,
                                      segment_ridges)


def test_thresholds_are_median_plus_k_robust_sigmas_of_gaussian_noise():
    values = np.abs(np.random.default_rng(5).normal(1.0, 0.1, 200_000)) + 10  # seed 5: N(11, 0.1)
    low, high = robust_thresholds(values, low_k=1.0, high_k=2.0)
    assert abs(low - 11.1) < 0.003 and abs(high - 11.2) < 0.003


def test_high_threshold_is_capped_so_the_strongest_pixels_seed_lines():
    values = np.random.default_rng(6).random(10_000)  # seed 6: uniform, no tail at all
    low, high = robust_thresholds(values, low_k=3.0, high_k=10.0)  # median + 10 sigma > max
    assert high == pytest.approx(np.quantile(values, 0.995)) and low <= high


def test_hysteresis_keeps_faint_part_connected_to_a_strong_part():
    # seed 7: background texture in 0-0.05 on every pixel
    response = np.random.default_rng(7).uniform(0, 0.05, (40, 60)).astype(np.float32)
    response[20, 5:55] = 0.1  # faint line (between the thresholds, about 0.08 and 0.14) ...
    response[20, 5:15] = 1.0  # ... with a strong stretch
    response[30, 5:55] = 0.1  # faint line alone
    binary = segment_ridges(response, low_k=3, high_k=6, min_size_px=5)
    assert binary[20, 5:55].all()
    assert not binary[30].any()


def test_small_objects_removed_by_size():
    binary = np.zeros((20, 20), dtype=bool)
    binary[2, 2:5] = True  # 3 px
    binary[10, 2:15] = True  # 13 px
    kept = remove_small_objects(binary, 5)
    assert not kept[2].any() and kept[10, 2:15].all()


def test_roi_mask_in_pixels_and_metres_agree():
    shape = (40, 60)
    rc = np.array([[5, 10], [5, 50], [30, 50], [30, 10]], dtype=float)
    m_per_px = 0.1
    uv = np.column_stack([(rc[:, 1] + 0.5) * m_per_px, (shape[0] - rc[:, 0] - 0.5) * m_per_px])
    a = roi_mask(rc, shape)
    b = roi_mask({"uv_m": uv}, shape, m_per_px=m_per_px)
    np.testing.assert_array_equal(a, b)
    assert a.sum() == 26 * 41


def test_roi_outside_the_image_raises_naming_roi():
    with pytest.raises(ValueError, match="roi lies outside"):
        roi_mask([[100, 100], [100, 200], [200, 200]], (50, 50))
    with pytest.raises(ValueError, match="roi"):
        roi_mask({"uv_m": [[0, 0], [1, 0], [1, 1]]}, (50, 50))  # metres without a scale
    with pytest.raises(ValueError, match="roi"):
        roi_mask([[0, 0], [1, 1]], (50, 50))


def test_zero_response_raises():
    with pytest.raises(ValueError, match="zero everywhere"):
        robust_thresholds(np.zeros((5, 5)), low_k=1, high_k=2)


def test_hysteresis_mask_keeps_only_pieces_holding_a_strong_pixel():
    from rockmass.imaging.segment import hysteresis_mask

    response = np.zeros((9, 20))
    response[2, 2:18] = 0.6  # weak line with one strong pixel: kept whole
    response[2, 9] = 0.95
    response[6, 2:18] = 0.6  # weak line alone: dropped
    mask = hysteresis_mask(response, low=0.5, high=0.9, min_size_px=1)
    assert mask[2].sum() == 16 and mask[6].sum() == 0 and mask.sum() == 16
    with pytest.raises(ValueError, match="low"):
        hysteresis_mask(response, low=0.9, high=0.5)


def test_fill_holes_closes_a_band_with_a_speck_so_it_thins_to_one_line():
    from rockmass.imaging.skeleton_graph import build_graph, skeletonize

    band = np.zeros((30, 80), bool)
    band[10:20, 5:75] = True
    band[13:17, 30:40] = False  # a brighter rib inside a wide dark band
    band[0:3, 0:3] = False  # background at the border is never a hole
    looped = build_graph(skeletonize(band))
    filled = fill_holes(band, 100)
    assert filled[13:17, 30:40].all() and not filled[:5].any()
    assert np.array_equal(fill_holes(band, 40), band)  # the 40 px hole is not under 40
    assert build_graph(skeletonize(filled)).n_branches < looped.n_branches
