"""Stress: random trace maps, near-parallel sets and every dangling rule keep the invariants."""

import numpy as np
import pytest

from rockmass.blockgen import JointSet, build, check_model, circle, horseshoe
from rockmass.blockgen.network import collapse_short

from ._fixtures import square


@pytest.mark.parametrize("seed", range(6))  # fixed seeds: random segment maps in a 10 m square
@pytest.mark.parametrize("dangling", ["glued", "drop"])
def test_random_trace_maps_give_valid_convex_models(seed, dangling):
    rng = np.random.default_rng(seed)
    centre = rng.uniform(0, 10, (60, 2))
    angle = rng.uniform(0, np.pi, 60)
    half = rng.uniform(0.5, 3.0, 60)[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    segs = np.stack([centre - half, centre + half], axis=1)
    m = build(square(10.0), traces=segs, excavations=[horseshoe((5, 4), 2.0, 1.0)],
              dangling=dangling)
    inv = check_model(m)
    assert inv["ok"], inv
    assert m.quality.concave_blocks_left == 0


def test_near_parallel_sets_keep_the_invariants():
    m = build(square(5.0), [JointSet(10.0, 0.4), JointSet(10.5, 0.45), JointSet(95, 0.7)],
              excavations=[circle((2.5, 2.5), 0.8)], seed=4)
    assert check_model(m)["ok"]


def test_collapse_short_merges_nodes_one_grid_cell_apart():
    grid = 2.0 ** -40
    segs = np.array([[[0, 0], [1, 0]], [[1, 0], [1 + grid, 0]], [[1 + grid, 0], [1, 1]]])
    out, n = collapse_short(segs, 1e-9, grid)
    assert n == 1 and len(out) == 2
    assert {tuple(p) for s in out for p in s} == {(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)}
