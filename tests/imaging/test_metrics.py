"""Accuracy metrics against hand-checkable maps: identity, offsets beyond the buffer, nodes, sets."""

import numpy as np
import pytest

from rockmass.accuracy import trace_accuracy
from rockmass.dfn import TraceMap
from rockmass.imaging.metrics import (buffered_match, count_nodes, pixels_within, raster_counts,
                                      set_mean_angles)

WINDOW = [[0, 0], [10, 0], [10, 10], [0, 10]]


def _grid():
    """Three horizontal and three vertical 8 m traces in a 10 m window: 9 crossings, 12 I ends."""
    segs = [[1, y, 9, y] for y in (2, 5, 8)] + [[x, 1, x, 9] for x in (2, 5, 8)]
    return TraceMap.from_segments(segs, {"set": [1, 1, 1, 2, 2, 2]}, window=WINDOW)


def test_identical_maps_score_perfectly():
    truth = _grid()
    acc = trace_accuracy(truth, truth, m_per_px=0.05)
    assert acc.f1 == pytest.approx(1.0) and acc.p21_rel_error == 0 and acc.p20_rel_error == 0
    assert acc.max_set_angle_error_deg == pytest.approx(0.0, abs=1e-9)
    assert acc.d_box_error == 0 and acc.node_count_error == 0


def test_offset_beyond_the_buffer_is_unmatched_and_within_is_matched():
    truth = TraceMap.from_segments([[1, 5, 9, 5]], window=WINDOW)
    near = TraceMap.from_segments([[1, 5.1, 9, 5.1]], window=WINDOW)  # 2 px at 0.05 m/px
    far = TraceMap.from_segments([[1, 5.25, 9, 5.25]], window=WINDOW)  # 5 px
    assert buffered_match(near, truth, m_per_px=0.05)[2] == pytest.approx(1.0)
    assert buffered_match(far, truth, m_per_px=0.05)[2] == pytest.approx(0.0)


def test_half_extracted_trace_has_recall_one_half_and_precision_one():
    truth = TraceMap.from_segments([[1, 5, 9, 5]], window=WINDOW)
    half = TraceMap.from_segments([[1, 5, 5, 5]], window=WINDOW)
    precision, recall, _ = buffered_match(half, truth, m_per_px=0.05)
    assert precision == pytest.approx(1.0)
    assert recall == pytest.approx(0.5 + 3 * 0.05 / 8, abs=0.01)  # the buffer reaches 3 px on


def test_node_counts_of_a_grid_a_t_and_window_edges():
    assert count_nodes(_grid(), snap_m=0.01) == {"I": 12, "Y": 0, "X": 9, "E": 0}
    t = TraceMap.from_segments([[0, 5, 10, 5], [5, 5, 5, 9]], window=WINDOW)
    assert count_nodes(t, snap_m=0.01) == {"I": 1, "Y": 1, "X": 0, "E": 2}


def test_set_means_of_two_tight_sets_by_doubled_angle_kmeans():
    rng = np.random.default_rng(8)  # seed 8: angles 20 +- 2 and 170 +- 2 degrees (wrap at 180)
    angles = np.concatenate([rng.normal(20, 2, 40), rng.normal(170, 2, 40)])
    d = np.column_stack([np.cos(np.radians(angles)), np.sin(np.radians(angles))])
    segs = np.hstack([np.full((80, 2), 5.0), 5.0 + d])
    means = set_mean_angles(TraceMap.from_segments(segs), 2)
    assert abs(means[0] - 20) < 1.5 and abs(means[1] - 170) < 1.5


def test_p21_error_is_relative_length_error():
    truth = _grid()
    shorter = TraceMap.from_segments(truth.segments() * [1, 1, 1, 1], window=WINDOW)
    longer = TraceMap.from_polylines([np.vstack([p[:1], p[1:] + (p[1:] - p[:1]) * 0.1])
                                      for p in (truth.polyline(i) for i in range(6))], window=WINDOW)
    assert trace_accuracy(shorter, truth, m_per_px=0.05).p21_rel_error == pytest.approx(0.0)
    assert trace_accuracy(longer, truth, m_per_px=0.05).p21_rel_error == pytest.approx(0.1)


def test_raster_match_scores_parallel_lines_by_their_distance():
    from rockmass.imaging.metrics import raster_match

    a = np.zeros((30, 40), bool)
    a[10, 5:35] = True
    b = np.zeros((30, 40), bool)
    b[14, 5:35] = True  # 4 px away
    assert raster_match(a, b, tolerance_px=5.0) == (1.0, 1.0, 1.0)
    assert raster_match(a, b, tolerance_px=3.0)[2] == 0.0


def test_raster_match_of_half_a_line_has_precision_one_and_recall_near_one_half():
    from rockmass.imaging.metrics import raster_match

    truth = np.zeros((20, 101), bool)
    truth[10, :100] = True
    half = np.zeros_like(truth)
    half[10, :50] = True
    precision, recall, _ = raster_match(half, truth, tolerance_px=5.0)
    assert precision == 1.0 and recall == pytest.approx(55 / 100)  # the tolerance reaches 5 px on


def test_raster_match_with_nothing_extracted_has_recall_zero():
    from rockmass.imaging.metrics import raster_match

    truth = np.zeros((10, 10), bool)
    truth[5, 2:8] = True
    precision, recall, f1 = raster_match(np.zeros_like(truth), truth)
    assert np.isnan(precision) and recall == 0.0 and f1 == 0.0


def test_pixels_within_counts_one_direction_of_the_raster_scores():
    rng = np.random.default_rng(5)
    a, b = rng.random((40, 60)) < 0.05, rng.random((40, 60)) < 0.02
    counts = raster_counts(a, b, tolerance_px=2.5)
    assert pixels_within(a, b, 2.5) == counts[:2]
    assert pixels_within(b, a, 2.5) == counts[2:]
    # by brute force: the pixels of a with a pixel of b within 2.5 px
    ra, rb = np.argwhere(a), np.argwhere(b)
    near = (np.hypot(*(ra[:, None, :] - rb[None, :, :]).transpose(2, 0, 1)) <= 2.5).any(axis=1)
    assert pixels_within(a, b, 2.5) == (int(near.sum()), int(a.sum()))
    # a reference without pixels matches none; any nonzero value is a pixel
    assert pixels_within(a, np.zeros_like(b), 2.5) == (0, int(a.sum()))
    assert pixels_within(a.astype(np.uint8) * 255, b, 2.5) == counts[:2]


@pytest.mark.parametrize("tolerance", [float("nan"), -1.0, float("inf")])
def test_pixels_within_refuses_a_tolerance_that_is_no_distance(tolerance):
    a = np.ones((4, 4), bool)
    with pytest.raises(ValueError, match="tolerance_px must be a finite distance"):
        pixels_within(a, a, tolerance)
    with pytest.raises(ValueError, match="mask and reference must be 2-D masks of one shape"):
        pixels_within(a, np.ones((4, 5), bool), 1.0)


def _band_around(v_m, shape=(200, 200), m_per_px=0.05, half_px=10):
    """An ignore mask: the rows within ``half_px`` of the horizontal line v = ``v_m``."""
    from rockmass.imaging.frame import uv_to_rc

    row = uv_to_rc(np.array([[0.0, v_m]]), shape[0], m_per_px)[0, 0]
    mask = np.zeros(shape, dtype=bool)
    mask[int(round(row)) - half_px:int(round(row)) + half_px + 1] = True
    return mask


def test_ignored_pixels_count_neither_as_drawn_nor_as_missed():
    # truth A (v = 2) and B (v = 8); drawn A and a false line C (v = 5): P = R = 1/2 scored whole
    truth = TraceMap.from_segments([[1, 2, 9, 2], [1, 8, 9, 8]], window=WINDOW)
    drawn = TraceMap.from_segments([[1, 2, 9, 2], [1, 5, 9, 5]], window=WINDOW)
    p, r, _ = buffered_match(drawn, truth, m_per_px=0.05, shape_px=(200, 200))
    assert p == pytest.approx(0.5, abs=0.01) and r == pytest.approx(0.5, abs=0.01)
    ignore = _band_around(8.0) | _band_around(5.0)          # B missed and C drawn, both ignored
    assert buffered_match(drawn, truth, m_per_px=0.05, ignore=ignore) == pytest.approx((1, 1, 1))
    only_b = _band_around(8.0)                              # C is scored: precision 1/2, recall 1
    p, r, _ = buffered_match(drawn, truth, m_per_px=0.05, ignore=only_b)
    assert p == pytest.approx(0.5, abs=0.01) and r == pytest.approx(1.0)


def test_trace_accuracy_outside_the_ignored_pixels():
    from rockmass.imaging.metrics import trace_accuracy as imaging_accuracy

    truth = TraceMap.from_segments([[1, 2, 9, 2], [1, 8, 9, 8], [5, 1, 5, 9]], {"set": [1, 1, 2]},
                                   window=WINDOW)
    # half of the vertical trace drawn, the whole of A, a false 8 m line on the ignored band
    drawn = TraceMap.from_segments([[1, 2, 9, 2], [5, 1, 5, 5], [1, 8.1, 9, 8.1]], window=WINDOW)
    ignore = _band_around(8.0)
    acc = imaging_accuracy(drawn, truth, m_per_px=0.05, ignore=ignore)
    # lengths outside the band: truth 8 + 8 - 21 px of the vertical one; drawn 8 + 4 (m)
    outside_true = 16.0 - 21 * 0.05
    assert acc.p21_rel_error == pytest.approx(12.0 / outside_true - 1.0, abs=0.01)
    assert acc.p20_rel_error == pytest.approx(0.0)          # 2 traces scored on either side
    assert acc.precision == pytest.approx(1.0)
    assert max(acc.set_angle_errors_deg) == pytest.approx(0.0, abs=1e-6)
    whole = imaging_accuracy(drawn, truth, m_per_px=0.05, shape_px=(200, 200))
    assert whole.p21_rel_error == pytest.approx(20.0 / 24.0 - 1.0, abs=1e-9)


def test_an_ignore_mask_of_another_shape_or_covering_the_truth_is_refused():
    from rockmass.imaging.metrics import trace_accuracy as imaging_accuracy

    truth = TraceMap.from_segments([[1, 2, 9, 2]], window=WINDOW)
    with pytest.raises(ValueError, match="shape"):
        buffered_match(truth, truth, m_per_px=0.05, shape_px=(200, 200), ignore=np.zeros((10, 10), bool))
    with pytest.raises(ValueError, match="ignore covers the truth"):
        imaging_accuracy(truth, truth, m_per_px=0.05, ignore=np.ones((200, 200), bool))
    with pytest.raises(ValueError, match="ignore covers the truth"):  # the truth's only trace
        imaging_accuracy(truth, truth, m_per_px=0.05, ignore=_band_around(2.0))
