"""Mauldon's circular-window estimators: single traces counted by hand, a Poisson oracle, circle detection."""

import math
import warnings

import numpy as np
import pytest
import shapely

from rockmass.dfn import TraceMap
from rockmass.dfn.intensity import sampling_window
from rockmass.dfn.mauldon import (circle_window, inscribed_circles, mauldon_circle, mauldon_circles,
                                  mauldon_from_counts)

from ._fixtures import CATALOGUE, poisson_segments



# -- the formulas -------------------------------------------------------------------------------


def test_formulas_match_mauldon_on_round_numbers():
    e = mauldon_from_counts(40, 10, 2.0)
    assert e.p21_per_m == 40 / 8  # n / (4r)
    assert e.p20_per_m2 == pytest.approx(10 / (2 * math.pi * 4))  # m / (2 pi r^2)
    assert e.mean_length_m == pytest.approx(math.pi * 2 / 2 * 40 / 10)  # (pi r / 2)(n / m)
    assert (e.valid, e.reason) == (True, "")


def test_no_end_inside_leaves_mean_length_undefined_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        e = mauldon_from_counts(6, 0, 1.0)
    assert math.isnan(e.mean_length_m)
    assert not e.valid and "m = 0" in e.reason
    assert (e.p21_per_m, e.p20_per_m2) == (1.5, 0.0)


def test_empty_circle_has_zero_intensity_and_undefined_mean_length():
    e = mauldon_circle(CATALOGUE["empty"].build(), (0, 0), 1.0)
    assert (e.n_intersections, e.n_endpoints, e.p21_per_m, e.valid) == (0, 0, 0.0, False)


@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        ((1, 1, 0.0), ValueError, "radius_m"),
        ((1, 1, -2.0), ValueError, "radius_m"),
        ((-1, 1, 1.0), ValueError, "n_intersections"),
        ((1, -1, 1.0), ValueError, "n_endpoints"),
        ((1.5, 1, 1.0), TypeError, "n_intersections"),
    ],
)
def test_bad_counts_and_radius_are_rejected_by_name(args, error, match):
    with pytest.raises(error, match=match):
        mauldon_from_counts(*args)


# -- counting n and m on single traces ----------------------------------------------------------


@pytest.mark.parametrize(
    ("segments", "n", "m"),
    [
        ([[-2, 0, 2, 0]], 2, 0),  # a diameter, through the circle
        ([[-2, 0.6, 2, 0.6]], 2, 0),  # a chord
        ([[-0.5, 0, 0.5, 0]], 0, 2),  # wholly inside
        ([[0, 0, 3, 0]], 1, 1),  # from the centre out
        ([[2, 2, 3, 3]], 0, 0),  # wholly outside
        ([[-2, 1, 2, 1]], 0, 0),  # tangent at (0, 1): a touch, not a crossing
        ([[0, 0, 1, 0]], 1, 1),  # from the centre to the circle exactly: the end on it is a crossing
    ],
)
def test_single_straight_traces_are_counted_by_hand(segments, n, m):
    e = mauldon_circle(TraceMap.from_segments(segments), (0, 0), 1.0)
    assert (e.n_intersections, e.n_endpoints) == (n, m)


def test_polyline_with_a_vertex_on_the_circle_counts_it_once():
    tm = TraceMap.from_polylines([[(0, 0), (1, 0), (2, 0)]])  # the vertex (1, 0) lies on the circle
    assert mauldon_circle(tm, (0, 0), 1.0).n_intersections == 1


def test_wiggly_trace_crossing_in_and_out_counts_every_crossing():
    tm = TraceMap.from_polylines([[(-2, 0), (0, 0), (0, 2), (0.5, 2), (0.5, -2)]])  # in, out, in, out
    assert mauldon_circle(tm, (0, 0), 1.0).n_intersections == 4


def test_ends_within_tolerance_of_the_circle_count_as_crossings_not_ends():
    tm = TraceMap.from_segments([[0, 0, 0.9995, 0], [0, 0.5, 0, 1.0004]])  # stop 0.5 mm short / 0.4 mm beyond
    exact = mauldon_circle(tm, (0, 0), 1.0)
    snapped = mauldon_circle(tm, (0, 0), 1.0, tolerance_m=0.001)
    assert (exact.n_intersections, exact.n_endpoints) == (1, 3)
    assert (snapped.n_intersections, snapped.n_endpoints) == (2, 2)


def test_traces_clipped_to_a_circle_count_the_same_as_uncut_traces():
    # seed 7: random chords and stubs; clipping them to the 64-gon must not change n or m
    rng = np.random.default_rng(7)
    segments = poisson_segments(rng, intensity_per_m2=3.0, length_m=1.5, region_radius_m=2.5)
    tm = TraceMap.from_segments(segments)
    disk = shapely.Point(0, 0).buffer(1.0, quad_segs=256)
    circle = circle_window(disk)
    parts = shapely.get_parts(shapely.intersection(tm.to_shapely(), disk))
    clipped = TraceMap.from_shapely(parts[(shapely.get_type_id(parts) == 1) & ~shapely.is_empty(parts)])
    uncut = mauldon_circle(tm, circle.centre_xy_m, circle.radius_m)
    cut = mauldon_circle(clipped, circle.centre_xy_m, circle.radius_m, tolerance_m=1e-5)
    # the 1024-gon lies inside its circle by at most 1 - cos(pi / 1024) ~ 4.7e-6 r: ends on it snap
    assert (cut.n_intersections, cut.n_endpoints) == (uncut.n_intersections, uncut.n_endpoints)


def test_centre_must_be_one_point():
    with pytest.raises(ValueError, match="centre_xy_m"):
        mauldon_circle(CATALOGUE["single_trace"].build(), (0, 0, 0), 1.0)


def test_radius_must_be_positive():
    with pytest.raises(ValueError, match="radius_m"):
        mauldon_circle(CATALOGUE["single_trace"].build(), (0, 0), 0.0)


# -- statistical oracle -------------------------------------------------------------------------


def test_mauldon_p21_p20_and_mean_length_match_a_poisson_segment_process():
    # seed 31415: 1 m segments, 30 per m², isotropic; circle of radius 4 m centred in a 5 m disc of
    # centres (4 + 1/2 < 5: stationary over the circle). True P21 = 30 m/m², P20 = 30 /m², mean 1 m.
    # n is compound Poisson with 0..2 hits a segment, so Var(n) <= 2 E[n], E[n] = 4 r P21 = 480;
    # likewise Var(m) <= 2 E[m], E[m] = 2 pi r² P20.
    rng = np.random.default_rng(31415)
    segments = poisson_segments(rng, intensity_per_m2=30.0, length_m=1.0, region_radius_m=5.0)
    r = 4.0
    e = mauldon_circle(TraceMap.from_segments(segments), (0.0, 0.0), r)
    expected_n, expected_m = 4 * r * 30.0, 2 * math.pi * r * r * 30.0
    assert abs(e.p21_per_m - 30.0) <= 3 * math.sqrt(2 * expected_n) / (4 * r)
    assert abs(e.p20_per_m2 - 30.0) <= 3 * math.sqrt(2 * expected_m) / (2 * math.pi * r * r)
    # ratio estimator: relative error below the sum of the two relative 3-sigma bounds
    bound = 3 * math.sqrt(2 / expected_n) + 3 * math.sqrt(2 / expected_m)
    assert abs(e.mean_length_m - 1.0) <= bound


# -- circle detection ---------------------------------------------------------------------------


@pytest.mark.parametrize("quad_segs", [8, 16, 64])
def test_buffered_points_are_circles_with_their_centre_and_radius(quad_segs):
    c = circle_window(shapely.Point(12.5, -3.0).buffer(2.5, quad_segs=quad_segs))
    assert c.is_circle and c.reason == ""
    assert c.centre_xy_m == pytest.approx((12.5, -3.0), abs=1e-9)
    assert c.radius_m == pytest.approx(2.5, rel=1e-9)
    # an inscribed regular 4q-gon deviates by 1 - cos(pi / 4q) at its edge midpoints
    assert c.max_rel_deviation == pytest.approx(1 - math.cos(math.pi / (4 * quad_segs)), rel=1e-6)


@pytest.mark.parametrize(
    "ring",
    [
        [(0, 0), (1, 0), (1, 1), (0, 1)],  # a square: its vertices are concyclic, its edges are not
        [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 12, endpoint=False)],  # a 12-gon
        [(2 * math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 200, endpoint=False)],  # ellipse
    ],
)
def test_polygons_that_are_not_circles_are_rejected_with_a_reason(ring):
    c = circle_window(ring)
    assert not c.is_circle and "not a circle" in c.reason


def test_circle_test_is_scale_and_position_free():
    small = circle_window(shapely.Point(0, 0).buffer(1e-3))
    far = circle_window(shapely.Point(5e5, 4.6e6).buffer(50.0))
    assert small.is_circle and far.is_circle
    assert far.radius_m == pytest.approx(50.0, rel=1e-6)


def test_circle_window_accepts_a_sampling_window():
    tm = TraceMap.from_segments([[0, 0, 1, 0]], window=shapely.Point(0, 0).buffer(2.0))
    assert circle_window(sampling_window(tm)).is_circle


def test_circle_tolerance_must_be_a_fraction():
    with pytest.raises(ValueError, match="rel_tolerance"):
        circle_window(shapely.Point(0, 0).buffer(1.0), rel_tolerance=1.5)


def test_circle_window_does_not_modify_its_input():
    ring = np.array([(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 64, endpoint=False)])
    before = ring.copy()
    circle_window(ring)
    assert np.array_equal(ring, before)


def test_mauldon_circle_does_not_modify_the_centre():
    centre = np.array([0.5, -0.25])
    mauldon_circle(CATALOGUE["crossing_pair"].build(), centre, 1.0)
    assert centre.tolist() == [0.5, -0.25]


# -- circles placed inside a window -------------------------------------------------------------

L_SHAPE = [(0, 0), (30, 0), (30, 10), (10, 10), (10, 30), (0, 30)]
WINDOWS = {
    "rectangle 3:1": [(0, 0), (30, 0), (30, 10), (0, 10)],
    "square": [(0, 0), (10, 0), (10, 10), (0, 10)],
    "L-shape": L_SHAPE,
    "triangle": [(0, 0), (12, 0), (3, 9)],
    "tilted rectangle": [(0, 0), (16, 12), (13, 16), (-3, 4)],
}


@pytest.mark.parametrize("name", sorted(WINDOWS))
def test_inscribed_circles_lie_inside_the_window_and_do_not_overlap(name):
    polygon = shapely.Polygon(WINDOWS[name])
    c = inscribed_circles(WINDOWS[name])
    assert c.n_circles >= 1 and 0 < c.radius_m <= c.largest_radius_m
    for centre in c.centres_xy_m:
        point = shapely.Point(centre)
        assert polygon.covers(point)
        assert polygon.exterior.distance(point) >= c.radius_m * (1 - 1e-9)  # the whole circle inside
    gaps = [np.hypot(*(a - b)) for i, a in enumerate(c.centres_xy_m) for b in c.centres_xy_m[i + 1:]]
    assert all(g >= 2 * c.radius_m * (1 - 1e-9) for g in gaps)


def test_a_three_to_one_rectangle_gets_three_circles_of_nine_tenths_its_half_width():
    c = inscribed_circles(WINDOWS["rectangle 3:1"])
    assert c.n_circles == 3
    assert c.radius_m == pytest.approx(4.5) and c.largest_radius_m == pytest.approx(5.0)
    np.testing.assert_allclose(c.centres_xy_m[:, 1], 5.0)  # centred across the width


def test_smaller_circles_pack_hexagonally():
    # radius 5 in a 40 m square: hexagonal rows 5 sqrt(3) apart fit 4 + 3 + 4 + 3 centres
    c = inscribed_circles([(0, 0), (40, 0), (40, 40), (0, 40)], radius_m=5.0)
    assert c.n_circles == 14


def test_a_radius_that_does_not_fit_is_rejected_with_the_largest_that_does():
    with pytest.raises(ValueError, match="radius_m.*largest inscribed circle has radius 5"):
        inscribed_circles(WINDOWS["rectangle 3:1"], radius_m=5.5)
    with pytest.raises(ValueError, match="radius_fraction"):
        inscribed_circles(WINDOWS["square"], radius_fraction=1.5)


def test_pooled_counts_over_one_circle_equal_the_single_circle_estimate():
    tm = TraceMap.from_segments([[1, 1, 4, 5], [2, 8, 8, 8], [6, 1, 6, 4], [5, 5, 15, 5]],
                                window=WINDOWS["square"])
    pooled = mauldon_circles(tm)
    single = mauldon_circle(tm, pooled.centres_xy_m[0], pooled.radius_m)
    assert pooled.n_circles == 1
    assert (pooled.p21_per_m, pooled.p20_per_m2, pooled.mean_length_m) == (
        single.p21_per_m, single.p20_per_m2, single.mean_length_m)


def test_a_trace_along_a_rectangle_crosses_each_circle_twice():
    tm = TraceMap.from_segments([[0, 5, 30, 5]], window=WINDOWS["rectangle 3:1"])
    e = mauldon_circles(tm)
    assert e.n_intersections.tolist() == [2, 2, 2] and e.n_endpoints.tolist() == [0, 0, 0]
    assert e.p21_per_m == pytest.approx(6 / (4 * 3 * 4.5))  # sum n / (4 k r)
    assert not e.valid and "m = 0" in e.reason and math.isnan(e.mean_length_m)


def test_pooled_mauldon_matches_a_poisson_segment_process_in_a_rectangle():
    # seed 11: isotropic segments of 1 m at 10 per m2 (P21 = 10, P20 = 10); a 40 x 20 m window gets
    # two circles of radius 9: E[sum n] = 4 k r P21 = 720, E[sum m] = 2 pi k r^2 P20 ~ 10 180
    rng = np.random.default_rng(11)
    rows = poisson_segments(rng, intensity_per_m2=10.0, length_m=1.0, region_radius_m=23.0)
    rows[:, [0, 2]] += 20.0
    rows[:, [1, 3]] += 10.0
    tm = TraceMap.from_segments(rows, window=[(0, 0), (40, 0), (40, 20), (0, 20)])
    e = mauldon_circles(tm)
    assert e.n_circles == 2 and e.radius_m == pytest.approx(9.0)
    # as for one circle: Var(sum n) <= 2 E[sum n], Var(sum m) <= 2 E[sum m] (0..2 hits per segment)
    expected_n, expected_m = 4 * 2 * 9.0 * 10.0, 2 * math.pi * 2 * 81.0 * 10.0
    assert abs(e.p21_per_m - 10.0) <= 3 * math.sqrt(2 * expected_n) / (4 * 2 * 9.0)
    assert abs(e.p20_per_m2 - 10.0) <= 3 * math.sqrt(2 * expected_m) / (2 * math.pi * 2 * 81.0)
    assert abs(e.mean_length_m - 1.0) <= 3 * math.sqrt(2 / expected_n) + 3 * math.sqrt(2 / expected_m)


def test_mauldon_circles_needs_a_window_or_circles():
    with pytest.raises(ValueError, match="window"):
        mauldon_circles(TraceMap.from_segments([[0, 0, 1, 1]]))
    with pytest.raises(TypeError, match="circles"):
        mauldon_circles(TraceMap.from_segments([[0, 0, 1, 1]]), circles=[(0, 0)])
