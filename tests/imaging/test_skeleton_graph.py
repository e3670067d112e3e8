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


def test_forked_line_end_keeps_the_straight_prong_not_the_longer_one():
    # a line ending in a fork of two short prongs, 5 px straight on and 7 diagonal steps (9.9 px)
    # to the side: the straight one continues the line (the longer one would hook its end)
    skel = np.zeros((40, 80), dtype=bool)
    skel[20, 5:51] = True  # the line, ending at the fork node (20, 50)
    skel[20, 51:56] = True  # straight prong, 5 px
    for k in range(1, 8):
        skel[20 + k, 50 + k] = True  # diagonal prong
    graph = prune_spurs(build_graph(skel), 10.0)
    assert graph.n_branches == 1
    branch = graph.branch(0)
    assert np.all(branch[:, 0] == 20) and branch[:, 1].max() == 55


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


def _line_with_texture_spur():
    """A 1-px vertical line that steps one column aside twice near a junction, as a skeleton does
    beside a small blob, and an 11-px spur from that junction, 24 degrees off the line (the
    pixels of a case met on a photograph)."""
    skel = np.zeros((300, 260), dtype=bool)
    skel[0:128, 200] = True
    skel[128:139, 201] = True
    skel[139, 202] = True  # the junction
    skel[140:147, 202] = True
    skel[147:300, 201] = True
    for r, c in [(130, 206), (131, 206), (132, 205), (133, 205), (134, 204), (135, 204), (136, 204),
                 (137, 204), (138, 203)]:
        skel[r, c] = True
    return skel


def test_short_dangling_spur_does_not_take_the_lines_continuation():
    # measured over 2-12 px, the line's two halves turn by 11.4 degrees through the junction and the
    # spur with the lower half by 10.2: pairing by turn alone chained the spur with the lower half
    # and left two traces overlapping beside the spur; the spur is a short dangling branch, ranked
    # 15 degrees worse, so the line is chained straight through
    graph = prune_spurs(build_graph(_line_with_texture_spur()), 10.0)
    assert graph.n_branches == 3  # the spur (10.7 px) survives pruning
    traces = chain_traces(graph, max_turn_deg=35.0, skip_px=2.0, reach_px=12.0)
    line = max(traces, key=_length)
    assert line[:, 0].min() == 0 and line[:, 0].max() == 299
    assert np.all(line[:, 1] <= 202)  # it does not run through the spur
    assert sorted(len(t) for t in traces) == [10, 300]  # one pixel a row, and the spur


def test_long_branch_beats_short_one_only_within_the_penalty():
    # a straight stub dangling 8 px past a junction keeps the line's continuation over a long branch
    # turning 30 degrees (15 + 0 < 30): the penalty ranks, it does not forbid
    skel = np.zeros((200, 200), dtype=bool)
    skel[100, 20:100] = True  # the line, coming from the left
    skel[100, 101:109] = True  # the straight stub, 8 px
    for k in range(1, 90):  # a long branch at 30 degrees
        skel[100 + round(k * np.sin(np.radians(30))), 100 + k] = True
    skel[100, 100] = True
    traces = chain_traces(build_graph(skel), max_turn_deg=35.0)
    straight = [t for t in traces if np.ptp(t[:, 0]) == 0]
    assert max(_length(t) for t in straight) >= 87


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


def test_end_directions_kernel_agrees_with_the_python_rule_to_the_bit():
    # the kernel replaces a per-branch Python loop over _direction: every branch end of real
    # skeletons (random crack networks) and of hand-made edge cases must come out bit for bit
    from rockmass.imaging.skeleton_graph import SkeletonGraph, _direction, end_directions

    rng = np.random.default_rng(3)
    image = np.zeros((300, 300), np.uint8)
    for _ in range(40):
        (r0, c0), (r1, c1) = rng.integers(0, 300, (2, 2))
        cv2.line(image, (int(c0), int(r0)), (int(c1), int(r1)), 1, int(rng.integers(1, 4)))
    graphs = [build_graph(skeletonize(image.astype(bool)))]
    cases = [np.array([[0.0, 0.0]]), np.array([[5.0, 5.0], [5.0, 5.0]]),  # one point; no length
             np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]),  # skip = reach / 3 on a vertex
             np.array([[4.0, 4.0], [4.0, 5.0], [4.0, 4.0]]),  # back to its start
             np.cumsum(rng.integers(-1, 2, (60, 2)), axis=0).astype(float)]  # a wandering chain
    offsets = np.cumsum([0] + [len(c) for c in cases])
    graphs.append(SkeletonGraph(np.zeros((1, 2)), np.concatenate(cases), offsets.astype(np.int64),
                                np.zeros(len(cases), np.int64), np.zeros(len(cases), np.int64),
                                -np.ones((len(cases), 2, 2), np.int64)))
    for graph in graphs:
        for skip, reach in [(2.0, 12.0), (0.0, 5.0), (3.0, 3.0)]:
            fast = end_directions(graph, skip_px=skip, reach_px=reach)
            for i in range(graph.n_branches):
                chain = graph.branch(i)
                assert np.array_equal(fast[i, 0], _direction(chain, skip, reach))
                assert np.array_equal(fast[i, 1], _direction(chain[::-1], skip, reach))
    assert graphs[0].n_branches > 50


def test_end_directions_refuse_what_the_kernel_cannot_measure_and_read_read_only_chains():
    import pytest

    from rockmass.imaging.skeleton_graph import _direction, chain_end_directions, end_directions

    chains = [np.array([[0.0, 0.0], [0.0, 30.0]]), np.array([[5.0, 5.0], [6.0, 6.0]])]
    with pytest.raises(ValueError, match="skip_px must be finite"):
        chain_end_directions(chains, skip_px=5.0, reach_px=float("nan"))  # read past a chain before
    with pytest.raises(ValueError, match="skip_px must be finite"):
        chain_end_directions(chains, skip_px=float("nan"))
    graph = build_graph(skeletonize(_thick([(10, 60, 110, 60)], width=1)))
    graph.branch_rc_px.setflags(write=False)  # a graph frozen by its maker
    graph.branch_offsets.setflags(write=False)
    np.testing.assert_array_equal(end_directions(graph)[0, 0], _direction(graph.branch(0), 2.0, 12.0))
    assert chain_end_directions([]).shape == (0, 2, 2)
