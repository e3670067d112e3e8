"""Noding through chains: segments joined into chains before GEOS give the same noded segments, in
the same order and orientation, as the segments given one by one."""

import numpy as np
import pytest
import shapely

from rockmass.blockgen.network import (_node_chains, _noded_pieces, collapse_short,
                                       dangling_extensions, exterior_coords, node, snap_to_grid)
from rockmass.blockgen._network_kernels import chain_segments

from .test_rays import GRID, _random_segments, _with_box


def _one_by_one(segments):
    """The reference: every segment its own GEOS line (zero-length pieces dropped, as node does)."""
    out = _noded_pieces(shapely.linestrings(segments), GRID)
    return out[np.any(out[:, 0] != out[:, 1], axis=1)]


def _network_with_extensions(seed, n=300, side=40.0):
    """A noded random network and the extensions of its dangling ends (the builder's second
    noding: one long run of connected segments, then the extensions)."""
    rng = np.random.default_rng(seed)
    segs = snap_to_grid(_with_box(_random_segments(rng, n, side), side), GRID)
    noded = collapse_short(node(segs, GRID), 1e-9 * side, GRID)[0]
    ext, _, _ = dangling_extensions(noded, GRID, 2 * side)
    return np.concatenate([noded, ext])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_chained_noding_gives_the_pieces_of_one_by_one_noding_in_the_same_order(seed):
    segments = _network_with_extensions(seed)
    chained = _node_chains(segments, GRID)
    assert chained is not None  # the chains paid and were traced back
    chained = chained[np.any(chained[:, 0] != chained[:, 1], axis=1)]
    assert np.array_equal(chained, _one_by_one(segments))
    assert np.array_equal(node(segments, GRID, chain=True), _one_by_one(segments))


def test_overlapping_segments_fall_back_to_one_by_one_noding():
    # a path and a segment lying on part of it: GEOS gives the shared piece once
    path = np.array([[[0, 0], [1, 0]], [[1, 0], [2, 0]], [[2, 0], [3, 0]], [[3, 0], [3, 1]]], float)
    overlap = np.array([[[2.5, 0], [1.5, 0]], [[1.5, 0], [1.5, -1]]])
    segments = np.concatenate([path, overlap])
    assert _node_chains(segments, GRID) is None
    assert np.array_equal(node(segments, GRID, chain=True), _one_by_one(segments))


def test_chains_hold_every_segment_once_and_are_continuous():
    segments = _network_with_extensions(3)
    bits = (segments.reshape(-1, 2) + 0.0).view(np.int64)
    _, ids = np.unique(bits, axis=0, return_inverse=True)
    ends = ids.reshape(-1, 2).astype(np.int64)
    seg, rev, start = chain_segments(ends, int(ends.max()) + 1)
    assert np.array_equal(np.sort(seg), np.arange(len(segments)))
    entry = np.where(rev, ends[seg, 1], ends[seg, 0])
    exit_ = np.where(rev, ends[seg, 0], ends[seg, 1])
    inner = np.ones(len(seg), bool)
    inner[start[:-1]] = False
    assert np.array_equal(entry[inner], exit_[np.flatnonzero(inner) - 1])
    assert len(start) - 1 < 0.5 * len(segments)


def test_exterior_coords_match_the_exterior_rings():
    square = shapely.Polygon([(0, 0), (4, 0), (4, 4), (0, 4)])
    holed = shapely.Polygon([(5, 0), (9, 0), (9, 4), (5, 4)], [[(6, 1), (6, 2), (7, 2), (7, 1)]])
    for faces in (np.array([square, square]), np.array([square, holed])):
        expected = shapely.get_coordinates(shapely.get_exterior_ring(faces), return_index=True)
        got = exterior_coords(faces)
        assert all(np.array_equal(a, b) for a, b in zip(got, expected))
