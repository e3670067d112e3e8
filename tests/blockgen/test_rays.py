"""Dangling-end rays: bounded rays on a spatial index hit exactly what one domain-long ray per end
hits, and their work grows with the number of ends, not with ends × segments."""

import numpy as np
import pytest

from rockmass.blockgen import build, check_model
from rockmass.blockgen import network
from rockmass.blockgen.network import _ray_hits, dangling_extensions, node, snap_to_grid

from ._fixtures import square

GRID = 2.0 ** -30


def _random_segments(rng, n, side, half_range=(0.5, 3.0)):
    """n segments with uniform centres in a side × side square, uniform angles and half-lengths."""
    centre = rng.uniform(0, side, (n, 2))
    angle = rng.uniform(0, np.pi, n)
    half = rng.uniform(*half_range, n)[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    return np.stack([centre - half, centre + half], axis=1)


def _with_box(segments, side):
    box = square(side)
    return np.concatenate([segments, np.stack([box, np.roll(box, -1, axis=0)], axis=1)])


def _end_rays(segments):
    """Both ends of every segment, pointing outwards along it (the rays of dangling ends)."""
    tip = np.concatenate([segments[:, 1], segments[:, 0]])
    d = np.concatenate([segments[:, 1] - segments[:, 0], segments[:, 0] - segments[:, 1]])
    return tip, d / np.hypot(d[:, 0], d[:, 1])[:, None]


def _brute_force_hits(origins, directions, segments, max_len):
    """Nearest crossing by the all-pairs double loop (the independent reference): ray p + t d meets
    segment a + s e where t = ((a − p) × e) / (d × e), s = ((a − p) × d) / (d × e), 0 <= s <= 1."""
    best = np.full(len(origins), np.inf)
    for i, (p, d) in enumerate(zip(origins, directions)):
        for a, b in segments:
            e = b - a
            denom = d[0] * e[1] - d[1] * e[0]
            if denom == 0:
                continue
            w = a - p
            t = (w[0] * e[1] - w[1] * e[0]) / denom
            s = (w[0] * d[1] - w[1] * d[0]) / denom
            if 0 <= s <= 1 and max_len * 1e-9 < t <= max_len:
                best[i] = min(best[i], t)
    return best


@pytest.mark.parametrize("seed", [0, 1, 2])  # fixed seeds: random segment maps in a 10 m square
def test_bounded_rays_hit_the_same_segments_as_a_brute_force_double_loop(seed):
    rng = np.random.default_rng(seed)
    segs = _with_box(_random_segments(rng, 40, 10.0), 10.0)
    tip, d = _end_rays(segs[:40])
    max_len = 2 * np.hypot(10.0, 10.0)
    t, _ = _ray_hits(tip, d, segs, max_len)
    ref = _brute_force_hits(tip, d, segs, max_len)
    assert 0.5 * len(ref) < np.isfinite(ref).sum() < len(ref)  # hits, and ends leaving the box
    np.testing.assert_array_equal(t, ref)


@pytest.mark.parametrize("first_len", [1e-3, 0.3, 5.0])
def test_the_first_ray_length_changes_the_work_not_the_hits(first_len):
    rng = np.random.default_rng(3)  # fixed seed
    segs = _with_box(_random_segments(rng, 150, 20.0), 20.0)
    tip, d = _end_rays(segs[:150])
    max_len = 2 * np.hypot(20.0, 20.0)
    long_t, long_pairs = _ray_hits(tip, d, segs, max_len, first_len=max_len)
    t, pairs = _ray_hits(tip, d, segs, max_len, first_len=first_len)
    np.testing.assert_array_equal(t, long_t)
    assert pairs < long_pairs


def test_a_ray_that_meets_nothing_within_max_len_gets_inf():
    segs = np.array([[[0.0, 0.0], [0.0, 1.0]], [[5.0, -1.0], [5.0, 1.0]]])
    t, _ = _ray_hits(np.array([[1.0, 0.0], [1.0, 0.0]]), np.array([[1.0, 0.0], [-1.0, 0.0]]),
                     segs, max_len=3.0, first_len=0.5)
    assert t[0] == np.inf  # the line at x = 5 lies 4 m away, beyond max_len
    assert t[1] == 1.0


def test_no_rays_or_no_segments_give_no_hits_and_no_work():
    t, pairs = _ray_hits(np.empty((0, 2)), np.empty((0, 2)), np.ones((3, 2, 2)), 1.0)
    assert t.shape == (0,) and pairs == 0
    t, pairs = _ray_hits(np.zeros((2, 2)), np.ones((2, 2)) / np.sqrt(2), np.empty((0, 2, 2)), 1.0)
    assert np.isinf(t).all() and pairs == 0


def _pairs_per_ray(side, domain_long=False):
    """Candidate pairs per dangling end on a noded random map of constant density (0.6 traces
    per m²) in a side × side square: the work of the ray search, counted, not timed.
    ``domain_long``: every ray cast at full length at once (the search before issue 20)."""
    rng = np.random.default_rng(11)  # fixed seed
    n = int(0.6 * side * side)
    segs = node(snap_to_grid(_with_box(_random_segments(rng, n, side), side), GRID), GRID)
    max_len = 2 * np.hypot(side, side)
    calls = []

    def counting(origins, directions, segments, max_len, **kw):
        if domain_long:
            kw["first_len"] = max_len
        out = _ray_hits(origins, directions, segments, max_len, **kw)
        calls.append((len(origins), out[1]))
        return out

    network._ray_hits = counting
    try:
        dangling_extensions(segs, GRID, max_len)
    finally:
        network._ray_hits = _ray_hits
    (n_rays, n_pairs), = calls
    return n_pairs / n_rays


def test_ray_work_per_dangling_end_stays_flat_as_the_map_grows():
    # 9x the traces at the same density: domain-long rays cross 3x more lines each (their work is
    # ends x segments overall); bounded rays stop near their first hit
    small, large = _pairs_per_ray(12.0), _pairs_per_ray(36.0)
    assert large < 1.3 * small
    long_small, long_large = _pairs_per_ray(12.0, True), _pairs_per_ray(36.0, True)
    assert long_large > 2.2 * long_small  # the counter sees the quadratic algorithm
    assert large < 0.3 * long_large


@pytest.mark.parametrize("dangling", ["glued", "joint"])
def test_blocks_are_identical_with_bounded_or_domain_long_rays(dangling, monkeypatch):
    rng = np.random.default_rng(5)  # fixed seed
    traces = _random_segments(rng, 300, 30.0)
    bounded = build(square(30.0), traces=traces, dangling=dangling)

    def domain_long(origins, directions, segments, max_len, **kw):
        return _ray_hits(origins, directions, segments, max_len, first_len=max_len)

    monkeypatch.setattr(network, "_ray_hits", domain_long)
    reference = build(square(30.0), traces=traces, dangling=dangling)
    assert check_model(bounded)["ok"]
    assert bounded.n_blocks == reference.n_blocks > 300
    np.testing.assert_array_equal(bounded.xy_m, reference.xy_m)
    np.testing.assert_array_equal(bounded.offsets, reference.offsets)
    np.testing.assert_array_equal(bounded.contact_blocks, reference.contact_blocks)
    np.testing.assert_array_equal(bounded.contact_kind, reference.contact_kind)
    assert bounded.quality.dangling == reference.quality.dangling
