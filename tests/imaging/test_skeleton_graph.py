"""Skeleton graph: nodes and branches of hand-drawn skeletons, spur pruning, X repair, gap bridging,
and straight-through chaining (answers worked out by hand)."""

import cv2
import numpy as np

from rockmass.imaging.skeleton_graph import (bridge_gaps, build_graph, chain_traces, prune_spurs,
                                             repair_crossings, skeletonize)


def _thick(lines, shape=(120, 120), width=5):
    """Binary mask of thick straight lines ((r0, c0, r1, c1) rows)."""
    img = np.zeros(shape, dtype=np.uint8)
    for r0, c0, r1, c1 in lines:
        cv2.line(img, (c0, r0), (c1, r1), 1, width)
    return img.astype(bool)


def _chain(mask, *, spur=10.0, link=10.0, bridge=25.0, angle=20.0):
    graph = prune_spurs(build_graph(skeletonize(mask)), spur)
    graph = repair_crossings(graph, max_link_px=link)
    graph = bridge_gaps(graph, max_distance_px=bridge, max_angle_deg=angle)
    return chain_traces(graph, min_length_px=5.0)


def _length(line):
    return float(np.hypot(*np.diff(line, axis=0).T).sum())


def test_straight_skeleton_is_one_branch_of_its_length():
    skel = np.zeros((20, 40), dtype=bool)
    skel[10, 5:36] = True
    graph = build_graph(skel)
    assert graph.n_branches == 1 and graph.n_nodes == 2
    assert graph.branch_lengths_px()[0] == 30.0
    assert sorted(graph.degrees().tolist()) == [1, 1]


def test_closed_loop_is_one_branch_at_one_node():
    img = np.zeros((40, 40), dtype=np.uint8)
    cv2.rectangle(img, (5, 5), (30, 30), 1, 1)
    graph = build_graph(img.astype(bool))
    assert graph.n_branches == 1 and graph.src[0] == graph.dst[0]
    # 4 sides of 25 px; each 4-connected corner is cut by a diagonal: 100 - 4 (2 - sqrt 2) at most
    assert 100 - 4 * (2 - np.sqrt(2)) * 2 <= graph.branch_lengths_px()[0] <= 100


def test_pixel_x_is_one_node_of_degree_four():
    skel = np.zeros((41, 41), dtype=bool)
    skel[20, 5:36] = True
    skel[5:36, 20] = True
    graph = build_graph(skel)
    assert graph.n_branches == 4 and sorted(graph.degrees().tolist()) == [1, 1, 1, 1, 4]


def test_three_pixel_spur_is_pruned_and_line_rejoined():
    skel = np.zeros((30, 60), dtype=bool)
    skel[15, 5:55] = True
    skel[12:15, 30] = True  # a 3-px spur
    graph = prune_spurs(build_graph(skel), 10.0)
    assert graph.n_branches == 1
    assert graph.branch_lengths_px()[0] == 49.0


def test_crossing_lines_give_two_traces_not_four():
    mask = _thick([(10, 60, 110, 60), (20, 10, 100, 110)], width=5)
    traces = _chain(mask)
    assert len(traces) == 2
    assert all(_length(t) > 80 for t in traces)


def test_t_stem_ends_at_the_bar():
    mask = _thick([(30, 10, 30, 110), (30, 60, 110, 60)], width=5)
    traces = sorted(_chain(mask), key=lambda t: np.ptp(t[:, 1]))
    assert len(traces) == 2
    stem, bar = traces
    top = stem[np.argmin(stem[:, 0])]
    assert abs(top[0] - 30) <= 3 and abs(top[1] - 60) <= 2  # the stem reaches the bar's centre line
    assert np.ptp(bar[:, 1]) > 95


def test_six_pixel_collinear_gap_is_bridged():
    mask = _thick([(60, 10, 60, 55), (60, 62, 60, 110)], width=3)  # 6 px gap between the lines
    traces = _chain(mask)
    assert len(traces) == 1
    assert np.ptp(traces[0][:, 1]) > 95


def test_gap_at_forty_degrees_is_not_bridged():
    end = np.array([60.0, 55.0])
    far = end + 6 * np.array([-np.sin(np.radians(40)), np.cos(np.radians(40))])
    tip = far + 50 * np.array([-np.sin(np.radians(40)), np.cos(np.radians(40))])
    mask = _thick([(60, 10, 60, 55), (int(far[0]), int(far[1]), int(tip[0]), int(tip[1]))], width=3)
    assert len(_chain(mask)) == 2


def test_bridging_respects_the_distance_limit():
    mask = _thick([(60, 10, 60, 45), (60, 75, 60, 110)], width=3)  # 30 px gap
    assert len(_chain(mask, bridge=25.0)) == 2
    assert len(_chain(mask, bridge=35.0)) == 1


def test_graph_functions_do_not_modify_their_input():
    skel = skeletonize(_thick([(10, 60, 110, 60), (20, 10, 100, 110)]))
    graph = build_graph(skel)
    before = (graph.branch_rc_px.copy(), graph.partners.copy(), graph.src.copy())
    bridge_gaps(repair_crossings(prune_spurs(graph, 10.0), max_link_px=10.0), max_distance_px=20.0)
    np.testing.assert_array_equal(graph.branch_rc_px, before[0])
    np.testing.assert_array_equal(graph.partners, before[1])
    np.testing.assert_array_equal(graph.src, before[2])
