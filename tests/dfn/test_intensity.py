"""Sampling window, P20, P21, raw mean length and scanline spacing: hand-counted maps and a Poisson oracle."""

import math

import numpy as np
import pytest
import shapely

from rockmass.dfn import TraceMap
from rockmass.dfn.intensity import (
    SamplingWindow,
    clipped_lengths_m,
    sampling_window,
    scanline_survey,
    trace_intensity,
)

from ._fixtures import CATALOGUE, SQUARE_10, intensity_square, poisson_segments



# -- window -------------------------------------------------------------------------------------


def test_window_argument_wins_over_the_maps_window():
    tm = TraceMap.from_segments([[1, 1, 2, 2]], window=SQUARE_10)
    w = sampling_window(tm, [(0, 0), (4, 0), (4, 4), (0, 4)])
    assert (w.source, w.area_m2) == ("argument", 16.0)


def test_maps_own_window_is_used_when_none_is_given():
    w = sampling_window(intensity_square())
    assert (w.source, w.area_m2) == ("trace_map", 100.0)


def test_bounding_box_stands_in_when_there_is_no_window():
    tm = TraceMap.from_segments([[1, 2, 4, 2], [2, 0, 2, 5]])
    w = sampling_window(tm)
    assert (w.source, w.area_m2, w.polygon.bounds) == ("bounding_box", 15.0, (1.0, 0.0, 4.0, 5.0))


def test_sampling_window_passes_through_unchanged():
    w = sampling_window(intensity_square())
    assert sampling_window(TraceMap.from_segments([[0, 0, 1, 1]]), w) is w


def test_shapely_polygon_window_is_accepted():
    tm = TraceMap.from_segments([[0, 0, 1, 1]])
    assert sampling_window(tm, shapely.box(0, 0, 2, 3)).area_m2 == 6.0


@pytest.mark.parametrize(
    ("window", "match"),
    [
        ([(0, 0), (1, 1)], "window"),  # two vertices
        ([(0, 0), (1, 0), (2, 0)], "window.*zero area"),
        ([(0, 0), (4, 4), (4, 0), (0, 2)], "window.*not a valid polygon"),  # a bow tie
    ],
)
def test_bad_window_is_rejected_naming_window(window, match):
    with pytest.raises(ValueError, match=match):
        sampling_window(TraceMap.from_segments([[0, 0, 1, 1]]), window)


def test_collinear_traces_without_window_raise_asking_for_one():
    tm = CATALOGUE["parallel_traces"].build().subset([0])  # one horizontal trace: a flat bounding box
    with pytest.raises(ValueError, match="window=.*zero area|zero area.*window="):
        sampling_window(tm)


def test_empty_map_without_window_raises():
    with pytest.raises(ValueError, match="0 traces"):
        trace_intensity(CATALOGUE["empty"].build())


def test_non_trace_map_raises_type_error():
    with pytest.raises(TypeError, match="trace_map"):
        trace_intensity([[0, 0, 1, 1]])


# -- P21, P20, mean length on the hand-counted square -------------------------------------------


def test_clipped_lengths_of_the_hand_counted_square():
    assert clipped_lengths_m(intensity_square()) == pytest.approx([5.0, 6.0, 3.0, 5.0], rel=1e-12)


def test_p21_is_clipped_length_per_area():
    r = trace_intensity(intensity_square())
    assert r.total_length_m == pytest.approx(19.0, rel=1e-12)
    assert r.p21_per_m == pytest.approx(0.19, rel=1e-12)


def test_p20_by_endpoints_counts_seven_inner_ends_as_three_and_a_half_traces():
    r = trace_intensity(intensity_square())
    assert (r.p20_rule, r.trace_count, r.p20_per_m2) == ("endpoints", 3.5, 0.035)


def test_p20_by_midpoints_counts_four_traces():
    r = trace_intensity(intensity_square(), p20_rule="midpoints")
    assert (r.trace_count, r.p20_per_m2) == (4.0, 0.04)


def test_raw_mean_length_is_clipped_total_over_traces_in_window():
    r = trace_intensity(intensity_square())
    assert (r.n_traces, r.mean_length_m, r.mean_length_valid) == (4, pytest.approx(4.75, rel=1e-12), True)


def test_edge_to_edge_grid_has_p21_exact_and_no_inner_ends():
    # 9 horizontal traces edge to edge in the 10 m square: P21 = 9 * 10 / 100
    tm = TraceMap.from_segments([[0, y, 10, y] for y in range(1, 10)], window=SQUARE_10)
    r = trace_intensity(tm)
    assert r.p21_per_m == pytest.approx(0.9, rel=1e-12)
    assert r.trace_count == 0.0


def test_traces_beyond_the_window_count_only_their_inside_part():
    inside = trace_intensity(TraceMap.from_segments([[0, 5, 10, 5]]), window=SQUARE_10)
    beyond = trace_intensity(TraceMap.from_segments([[-30, 5, 40, 5]]), window=SQUARE_10)
    assert beyond.p21_per_m == pytest.approx(inside.p21_per_m, rel=1e-12) == 0.1


def test_trace_outside_the_window_adds_nothing():
    tm = TraceMap.from_segments([[1, 1, 4, 5], [20, 20, 30, 30]], window=SQUARE_10)
    r = trace_intensity(tm)
    assert (r.n_traces, r.total_length_m, r.trace_count) == (1, 5.0, 1.0)


def test_edge_tolerance_turns_a_near_edge_end_into_a_censored_one():
    tm = TraceMap.from_segments([[5, 5, 9.995, 5]], window=SQUARE_10)  # ends 5 mm from the right edge
    assert trace_intensity(tm).trace_count == 1.0
    assert trace_intensity(tm, edge_tolerance_m=0.01).trace_count == 0.5


def test_empty_map_in_a_window_has_zero_intensity_and_no_mean_length():
    r = trace_intensity(CATALOGUE["empty"].build(), window=SQUARE_10)
    assert (r.p20_per_m2, r.p21_per_m, r.mean_length_valid) == (0.0, 0.0, False)
    assert math.isnan(r.mean_length_m)


def test_intensities_scale_with_the_unit_of_length():
    # the same map in decimetres: lengths x10, areas x100, so P21 /10 and P20 /100
    metres = intensity_square()
    decimetres = TraceMap(metres.xy_m * 10, metres.offsets, window_xy_m=metres.window_xy_m * 10)
    a, b = trace_intensity(metres), trace_intensity(decimetres)
    assert b.p21_per_m == pytest.approx(a.p21_per_m / 10, rel=1e-12)
    assert b.p20_per_m2 == pytest.approx(a.p20_per_m2 / 100, rel=1e-12)
    assert b.mean_length_m == pytest.approx(a.mean_length_m * 10, rel=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"p20_rule": "centres"}, ValueError, "p20_rule"),
        ({"edge_tolerance_m": -1.0}, ValueError, "edge_tolerance_m"),
        ({"edge_tolerance_m": math.nan}, ValueError, "edge_tolerance_m"),
        ({"edge_tolerance_m": "1"}, TypeError, "edge_tolerance_m"),
    ],
)
def test_bad_arguments_are_rejected_by_name(kwargs, error, match):
    with pytest.raises(error, match=match):
        trace_intensity(intensity_square(), **kwargs)


def test_window_argument_is_not_modified():
    window = np.array(SQUARE_10, dtype=float)
    before = window.copy()
    trace_intensity(intensity_square(), window=window)
    scanline_survey(intensity_square(), 30.0, window=window)
    assert np.array_equal(window, before) and window.flags.writeable


def test_p20_by_endpoints_is_unbiased_on_a_poisson_network():
    # seed 20240611: a Poisson process of 1 m segments, 40 per m²; the 4 m x 4 m window stays well
    # inside the 5 m disc of centres. 2m ~ Poisson-compound with Var(m) <= 2 E[m] (each segment has
    # 0, 1 or 2 ends inside), E[m] = 2 x 40 x 16 = 1280: 3 sigma is 3 sqrt(2 x 1280) / 2 traces.
    rng = np.random.default_rng(20240611)
    segments = poisson_segments(rng, intensity_per_m2=40.0, length_m=1.0, region_radius_m=5.0)
    window = [(-2, -2), (2, -2), (2, 2), (-2, 2)]
    r = trace_intensity(TraceMap.from_segments(segments), window=window)
    expected = 40.0 * 16.0
    assert abs(r.trace_count - expected) <= 3.0 * math.sqrt(2.0 * 2.0 * expected) / 2.0
    # P21 = 40 x 1 m/m²: the clipped length in the window, same compound bound with lengths <= 1 m
    assert abs(r.total_length_m - 40.0 * 16.0) <= 3.0 * math.sqrt(40.0 * 16.0 * 1.0)


# -- scanlines ----------------------------------------------------------------------------------


def test_scanlines_across_a_horizontal_grid_measure_its_spacing():
    tm = TraceMap.from_segments([[0, y, 10, y] for y in (1, 3, 5, 7, 9)])
    s = scanline_survey(tm, 0.0, window=SQUARE_10, line_spacing_m=1.0)
    assert s.scanline_angle_deg == 90.0
    assert s.offsets_m.size == 10
    assert s.lengths_m == pytest.approx(np.full(10, 10.0), rel=1e-12)
    assert s.n_intersections.tolist() == [5] * 10
    assert (s.mean_spacing_m, s.p10_per_m, s.valid) == (2.0, 0.5, True)


def test_scanlines_follow_an_oblique_set_in_a_rotated_window():
    # a square of side 8 rotated by 30°, and a set along one side: 4 traces at perpendicular offsets
    # 1, 3, 5, 7 m, each spanning the square, so every scanline normal to the set crosses 4 traces in
    # 8 m: spacing exactly 2 m
    t = math.radians(30.0)
    along, normal = np.array([math.cos(t), math.sin(t)]), np.array([-math.sin(t), math.cos(t)])
    window = [tuple(a * 8 * along + b * 8 * normal) for a, b in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    segments = [np.r_[d * normal, 8 * along + d * normal] for d in (1, 3, 5, 7)]
    s = scanline_survey(TraceMap.from_segments(segments), 30.0, window=window, line_spacing_m=0.5)
    assert s.scanline_angle_deg == pytest.approx(120.0)
    assert s.lengths_m == pytest.approx(np.full(s.offsets_m.size, 8.0), rel=1e-9)
    assert s.mean_spacing_m == pytest.approx(2.0, rel=1e-12)


def test_set_angle_is_axial():
    tm = TraceMap.from_segments([[0, y, 10, y] for y in (1, 3, 5, 7, 9)])
    a = scanline_survey(tm, 0.0, window=SQUARE_10)
    b = scanline_survey(tm, 180.0, window=SQUARE_10)
    assert a.mean_spacing_m == b.mean_spacing_m and a.set_angle_deg == b.set_angle_deg == 0.0


def test_default_scanlines_are_ten_across_the_window():
    s = scanline_survey(intensity_square(), 0.0)
    assert s.offsets_m.tolist() == pytest.approx([0.5 + k for k in range(10)])


def test_scanlines_parallel_to_the_traces_find_no_spacing():
    # the grid is horizontal; scanlines normal to a vertical "set" run horizontally, along the traces
    tm = TraceMap.from_segments([[0, y, 10, y] for y in (1.25, 3.25)])
    s = scanline_survey(tm, 90.0, window=SQUARE_10, line_spacing_m=1.0)
    assert (s.total_intersections, s.valid) == (0, False)
    assert math.isnan(s.mean_spacing_m) and "no trace" in s.reason


def test_concave_window_clips_scanlines_to_its_pieces():
    # a U-shaped window (10 x 10 minus the notch 4..6 x 2..10): a vertical scanline at x = 5 is 2 m long
    u_shape = [(0, 0), (10, 0), (10, 10), (6, 10), (6, 2), (4, 2), (4, 10), (0, 10)]
    tm = TraceMap.from_segments([[0, 1, 10, 1]])
    s = scanline_survey(tm, 0.0, window=u_shape, line_spacing_m=10.0)
    assert s.offsets_m.tolist() == [5.0]
    assert s.lengths_m == pytest.approx([2.0]) and s.n_intersections.tolist() == [1]


def test_scanline_spacing_must_be_positive():
    with pytest.raises(ValueError, match="line_spacing_m"):
        scanline_survey(intensity_square(), 0.0, line_spacing_m=0.0)


def test_sampling_window_object_keeps_its_source():
    w = SamplingWindow(shapely.box(0, 0, 10, 10), "argument")
    assert trace_intensity(intensity_square(), window=w).window_source == "argument"
