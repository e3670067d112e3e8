"""Sanderson & Nixon topology: hand-drawn networks, snap tolerance, a naive O(n²) oracle, identities."""

import math

import numpy as np
import pytest
import shapely

from rockmass.dfn import TraceMap
from rockmass.dfn.topology import trace_topology

from ._fixtures import CATALOGUE, SQUARE_10, TOPOLOGY_CASES

CASES = list(TOPOLOGY_CASES)


def counts(t):
    return {"I": t.n_i, "Y": t.n_y, "X": t.n_x, "E": t.n_e}



# -- hand-drawn networks ------------------------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_node_counts_match_hand_counts(name):
    case = TOPOLOGY_CASES[name]
    t = trace_topology(case.build(), snap_tolerance_m=case.tolerance_m)
    assert counts(t) == case.counts


@pytest.mark.parametrize("name", CASES)
def test_connections_per_trace_match_hand_counts(name):
    case = TOPOLOGY_CASES[name]
    t = trace_topology(case.build(), snap_tolerance_m=case.tolerance_m)
    assert t.connections.tolist() == case.connections


@pytest.mark.parametrize(
    ("name", "branches"),
    [("x", 4), ("t", 3), ("isolated", 1), ("plus_with_abutting_arm", 6), ("edge_censored", 2.5)],
)
def test_branch_formula_gives_the_branches_counted_by_eye(name, branches):
    # x: four arms; t: bar halves + stem; plus_with_abutting_arm: bar 2, vertical 3, arm 1.
    # edge_censored: (I + 4X)/2 = 2.5 -- E ends are left out of the formula, as in fractopo
    case = TOPOLOGY_CASES[name]
    assert trace_topology(case.build(), snap_tolerance_m=case.tolerance_m).n_branches == branches


def test_two_half_stems_abutting_at_one_point_are_two_y_nodes():
    # the formula then counts (4 + 3 x 2)/2 = 5 branches where the merged "+" has 4: digitise the
    # vertical as one trace to get an X node
    case = TOPOLOGY_CASES["plus_of_two_abutting_halves"]
    t = trace_topology(case.build(), snap_tolerance_m=case.tolerance_m)
    assert (t.n_y, t.n_branches) == (2, 5.0)
    assert t.abutted_trace[1:].tolist() == [[0, -1], [-1, 0]]


def test_connections_per_line_of_an_x_and_a_t_is_one():
    for name in ("x", "t"):  # C_L = 2 (X + Y) / ((I + Y) / 2) = 2 / 2
        case = TOPOLOGY_CASES[name]
        assert trace_topology(case.build(), snap_tolerance_m=case.tolerance_m).connections_per_line == 1.0


def test_connections_per_branch_of_a_t():
    case = TOPOLOGY_CASES["t"]  # (3 Y + 4 X) / N_B = 3 / 3
    assert trace_topology(case.build(), snap_tolerance_m=case.tolerance_m).connections_per_branch == 1.0


def test_y_end_names_the_trace_it_abuts():
    case = TOPOLOGY_CASES["t"]
    t = trace_topology(case.build(), snap_tolerance_m=case.tolerance_m)
    assert t.end_class.tolist() == [["I", "I"], ["Y", "I"]]
    assert t.abutted_trace.tolist() == [[-1, -1], [0, -1]]


def test_edge_ends_mark_their_traces_censored():
    case = TOPOLOGY_CASES["edge_censored"]
    t = trace_topology(case.build(), snap_tolerance_m=case.tolerance_m)
    assert t.censored.tolist() == [True, True]
    assert t.end_class.tolist() == [["E", "E"], ["I", "E"]]


def test_end_to_end_contact_is_flagged_on_i_nodes():
    case = TOPOLOGY_CASES["end_to_end"]
    t = trace_topology(case.build(), snap_tolerance_m=case.tolerance_m)
    assert t.end_contact.tolist() == [[False, True], [True, False]]


def test_crossing_at_a_polyline_vertex_is_one_x_node():
    tm = TraceMap.from_polylines([[(-1, 0), (0, 0), (1, 0)], [(0, -1), (0, 1)]])
    t = trace_topology(tm, snap_tolerance_m=0.01)
    assert counts(t) == {"I": 4, "Y": 0, "X": 1, "E": 0}
    assert t.x_nodes_xy_m.tolist() == [[0.0, 0.0]] and t.x_node_traces.tolist() == [[0, 1]]


def test_curved_trace_crossing_another_twice_makes_two_x_nodes():
    tm = TraceMap.from_polylines([[(-2, 0), (2, 0)], [(-1, -1), (-1, 1), (1, 1), (1, -1)]])
    assert trace_topology(tm, snap_tolerance_m=0.01).n_x == 2


def test_overlapping_traces_are_reported_not_counted_as_nodes():
    tm = TraceMap.from_segments([[0, 0, 2, 0], [1, 0, 3, 0]])  # share the piece 1..2
    t = trace_topology(tm, snap_tolerance_m=0.001)
    assert (t.n_x, t.n_overlapping_pairs) == (0, 1)


# -- window and tolerance -----------------------------------------------------------------------


def test_without_any_window_there_are_no_e_nodes():
    tm = TraceMap.from_segments([[0, 5, 10, 5], [5, 2, 5, 10]])
    t = trace_topology(tm, snap_tolerance_m=0.01)
    assert (t.n_e, t.has_window, t.censored.any()) == (0, False, False)


def test_the_maps_window_is_used_when_none_is_given():
    tm = TraceMap.from_segments([[0, 5, 10, 5]], window=SQUARE_10)
    assert trace_topology(tm, snap_tolerance_m=0.01).n_e == 2


def test_ends_outside_the_window_are_e_nodes_and_crossings_outside_are_dropped():
    # a "+" centred at (12, 5), outside the 10 m square, and a trace reaching in from it
    tm = TraceMap.from_segments([[11, 5, 13, 5], [12, 4, 12, 6], [12, 5.5, 5, 5.5]])
    t = trace_topology(tm, snap_tolerance_m=0.01, window=SQUARE_10)
    assert counts(t) == {"I": 1, "Y": 0, "X": 0, "E": 5}


def test_near_edge_end_becomes_e_within_the_snap_tolerance():
    tm = TraceMap.from_segments([[5, 5, 9.95, 5]])  # 5 cm from the right edge
    assert trace_topology(tm, snap_tolerance_m=0.01, window=SQUARE_10).n_e == 0
    assert trace_topology(tm, snap_tolerance_m=0.1, window=SQUARE_10).n_e == 1


def test_zero_tolerance_still_catches_ends_computed_by_intersection():
    # the stem ends where shapely put the bar's crossing with another line; that point is 1.2e-16 m
    # off the bar (checked below), so only the rounding floor of the tolerance makes the end a Y node
    bar = [8.574042765875694, 0.33585575305464355, 7.29655446429944, 1.7565562060255901]
    guide = shapely.LineString([(5.436249914654229, 9.350724237877682), (8.158535541215322, 0.02738500170148095)])
    end = shapely.intersection(guide, shapely.LineString([bar[:2], bar[2:]]))
    assert shapely.distance(end, shapely.LineString([bar[:2], bar[2:]])) > 0.0
    tm = TraceMap.from_segments([bar, [end.x, end.y, end.x, 5.0]])
    t = trace_topology(tm, snap_tolerance_m=0.0)
    assert (t.n_y, t.snap_tolerance_m > 0.0) == (1, True)


def test_snap_tolerance_must_be_non_negative_and_finite():
    tm = CATALOGUE["crossing_pair"].build()
    with pytest.raises(ValueError, match="snap_tolerance_m"):
        trace_topology(tm, snap_tolerance_m=-0.1)
    with pytest.raises(ValueError, match="snap_tolerance_m"):
        trace_topology(tm, snap_tolerance_m=math.inf)
    with pytest.raises(TypeError, match="snap_tolerance_m"):
        trace_topology(tm, snap_tolerance_m=None)


def test_empty_map_has_no_nodes_and_undefined_connectivity():
    t = trace_topology(CATALOGUE["empty"].build(), snap_tolerance_m=0.1)
    assert counts(t) == {"I": 0, "Y": 0, "X": 0, "E": 0}
    assert t.n_branches == 0.0 and math.isnan(t.connections_per_line) and math.isnan(t.connections_per_branch)


def test_window_argument_is_not_modified():
    window = np.array(SQUARE_10, dtype=float)
    before = window.copy()
    trace_topology(TOPOLOGY_CASES["x"].build(), snap_tolerance_m=0.01, window=window)
    assert np.array_equal(window, before)


# -- invariances and an independent oracle ------------------------------------------------------


def _random_network(seed, n=60):
    """Random segments in and around the 10 m square, a third of them re-aimed to end on another."""
    rng = np.random.default_rng(seed)
    start = rng.uniform(-1, 11, (n, 2))
    angle = rng.uniform(0, math.pi, n)
    length = rng.uniform(0.5, 4.0, n)
    end = start + length[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    for i in range(0, n, 3):  # end exactly on the interior of trace i + 1: a T junction
        j = (i + 1) % n
        end[i] = start[j] + rng.uniform(0.3, 0.7) * (end[j] - start[j])
    return np.hstack([start, end])


def _point_segment_distance(p, a, b):
    ab, ap = b - a, p - a
    t = min(max(float(ap @ ab) / float(ab @ ab), 0.0), 1.0)
    return float(np.hypot(*(p - (a + t * ab))))


def _segment_intersection(a, b, c, d):
    r, s = b - a, d - c
    denominator = r[0] * s[1] - r[1] * s[0]
    if denominator == 0.0:
        return None
    t = ((c - a)[0] * s[1] - (c - a)[1] * s[0]) / denominator
    u = ((c - a)[0] * r[1] - (c - a)[1] * r[0]) / denominator
    return a + t * r if 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0 else None


def _naive_topology(segments, tol, lo=0.0, hi=10.0):
    """Node counts and per-trace connections by plain double loops over straight traces (square window)."""
    seg = [(np.array(s[:2]), np.array(s[2:])) for s in segments]
    n = len(seg)
    node = {"I": 0, "Y": 0, "X": 0, "E": 0}
    connections = [0] * n
    for i, ends in enumerate(seg):
        for p in ends:
            if min(p[0] - lo, hi - p[0], p[1] - lo, hi - p[1]) <= tol:  # outside, or near the edge
                node["E"] += 1
                continue
            best = None
            for j, (a, b) in enumerate(seg):
                if j == i:
                    continue
                d = _point_segment_distance(p, a, b)
                if d <= tol and np.hypot(*(p - a)) > tol and np.hypot(*(p - b)) > tol and (best is None or d < best[0]):
                    best = (d, j)
            if best is None:
                node["I"] += 1
            else:
                node["Y"] += 1
                connections[i] += 1
                connections[best[1]] += 1
    for i in range(n):
        for j in range(i + 1, n):
            q = _segment_intersection(*seg[i], *seg[j])
            if q is None or not (lo <= q[0] <= hi and lo <= q[1] <= hi):
                continue
            if all(np.hypot(*(q - e)) > tol for e in (*seg[i], *seg[j])):
                node["X"] += 1
                connections[i] += 1
                connections[j] += 1
    return node, connections


@pytest.mark.parametrize("seed", [3, 11, 2024])  # three fixed random networks
def test_counts_match_a_naive_double_loop(seed):
    segments = _random_network(seed)
    t = trace_topology(TraceMap.from_segments(segments), snap_tolerance_m=0.05, window=SQUARE_10)
    node, connections = _naive_topology(segments, 0.05)
    assert counts(t) == node
    assert t.connections.tolist() == connections


@pytest.mark.parametrize("seed", [3, 11])
def test_connections_sum_to_twice_x_plus_y(seed):
    t = trace_topology(TraceMap.from_segments(_random_network(seed)), snap_tolerance_m=0.05, window=SQUARE_10)
    assert t.connections.sum() == 2 * (t.n_x + t.n_y)


def test_every_end_of_an_uncensored_network_is_i_or_y():
    # segments well inside the window: I + Y = 2 n, so the node count N_L equals the trace count
    rng = np.random.default_rng(5)  # seed 5
    start = rng.uniform(2, 8, (40, 2))
    segments = np.hstack([start, start + rng.uniform(-1.5, 1.5, (40, 2))])
    t = trace_topology(TraceMap.from_segments(segments), snap_tolerance_m=1e-6, window=SQUARE_10)
    assert t.n_i + t.n_y == 80 and t.n_lines == 40


def test_counts_do_not_depend_on_trace_order_or_direction():
    segments = _random_network(11)
    base = trace_topology(TraceMap.from_segments(segments), snap_tolerance_m=0.05, window=SQUARE_10)
    order = np.random.default_rng(0).permutation(len(segments))  # seed 0: any permutation
    flipped = segments[order][:, [2, 3, 0, 1]]
    other = trace_topology(TraceMap.from_segments(flipped), snap_tolerance_m=0.05, window=SQUARE_10)
    assert counts(other) == counts(base)
    assert np.array_equal(other.connections, base.connections[order])
    assert np.array_equal(other.end_class, base.end_class[order][:, ::-1])


def test_ten_thousand_traces_keep_the_connection_identity():
    # seed 99: 10^4 random segments in a 100 m square (the STRtree keeps this well under a second)
    rng = np.random.default_rng(99)
    start = rng.uniform(0, 100, (10_000, 2))
    segments = np.hstack([start, start + rng.uniform(-2, 2, (10_000, 2))])
    window = [(0, 0), (100, 0), (100, 100), (0, 100)]
    t = trace_topology(TraceMap.from_segments(segments), snap_tolerance_m=0.01, window=window)
    assert t.connections.sum() == 2 * (t.n_x + t.n_y)
    assert t.n_i + t.n_y + t.n_e == 20_000
