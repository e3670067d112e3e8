"""The broad phase and pair remapping written in plain loops (fast to compile) against numpy
references; each helper compiled for one signature only."""

from __future__ import annotations

import numpy as np
import pytest

from rockmass.solver import _kernels as K


def _boxes(nb: int, seed: int):
    """World vertex table of ``nb`` random quadrilaterals, with ties in x and inactive blocks."""
    rng = np.random.default_rng(seed)
    off = np.arange(0, 4 * nb + 1, 4, dtype=np.int64)
    centre = rng.uniform(0.0, 30.0, (nb, 2))
    wv = np.zeros((4 * nb, K.N_WV_COLUMNS))
    wv[:, :2] = np.repeat(centre, 4, axis=0) + rng.uniform(-1.0, 1.0, (4 * nb, 2))
    if nb > 6:  # equal smallest x in two blocks: the stable order of the sweep decides
        wv[off[3]:off[4], 0] = wv[off[5]:off[6], 0].min()
    active = rng.random(nb) > 0.1
    movable = rng.random(nb) > 0.2
    group = np.where(rng.random(nb) > 0.7, rng.integers(0, 3, nb), -1).astype(np.int64)
    return wv, off, active, movable, group


def _reference_pairs(wv, off, active, movable, group, margin):
    """Every pair (a < b) whose grown boxes overlap, by brute force, sorted by (a, b)."""
    nb = len(off) - 1
    lo = np.array([wv[off[b]:off[b + 1], :2].min(axis=0) - margin for b in range(nb)])
    hi = np.array([wv[off[b]:off[b + 1], :2].max(axis=0) + margin for b in range(nb)])
    pairs = [(a, b) for a in range(nb) for b in range(a + 1, nb)
             if active[a] and active[b] and (movable[a] or movable[b])
             and not (group[a] >= 0 and group[a] == group[b])
             and np.all(lo[b] <= hi[a]) and np.all(lo[a] <= hi[b])]
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


@pytest.mark.parametrize("nb, seed", [(1, 0), (2, 1), (40, 2), (400, 3)])
def test_broad_phase_finds_every_overlapping_pair_in_order(nb, seed):
    wv, off, active, movable, group = _boxes(nb, seed)
    pa, pb = K.broad_phase(wv, off, active, movable, group, 0.25)
    ref = _reference_pairs(wv, off, active, movable, group, 0.25)
    assert np.array_equal(np.column_stack([pa, pb]).reshape(-1, 2), ref)


def test_stable_argsort_is_numpy_mergesort():
    rng = np.random.default_rng(4)
    for n in (0, 1, 2, 7, 64, 1000):
        keys = np.round(rng.normal(size=n), 1)  # many ties
        if n > 5:
            keys[[1, 4]] = np.nan
        assert np.array_equal(K._stable_argsort(keys, n), np.argsort(keys, kind="mergesort"))


def test_remap_pairs_finds_block_model_contacts_like_searchsorted():
    nb = 50
    rng = np.random.default_rng(5)
    init_key = np.unique(rng.integers(0, nb * nb, 200)).astype(np.int64)
    new = np.unique(rng.integers(0, nb * nb, 300))
    new_pa, new_pb = (new // nb).astype(np.int64), (new % nb).astype(np.int64)
    keep = new_pa < new_pb
    new_pa, new_pb = new_pa[keep], new_pb[keep]
    n = len(new_pa)
    empty_i = np.zeros(0, np.int64)
    S = np.zeros((n, 2, K.N_SLOT_COLUMNS))
    pref, pinit, pprop = (np.zeros(n, np.int64) for _ in range(3))
    init_prop = np.arange(len(init_key), dtype=np.int64) + 10
    K.remap_pairs(empty_i, empty_i, np.zeros((0, 2, K.N_SLOT_COLUMNS)), empty_i, empty_i, new_pa,
                  new_pb, nb, S, pref, pinit, pprop, init_key, init_prop, 3,
                  np.zeros(len(init_key)))
    key = new_pa * nb + new_pb
    j = np.searchsorted(init_key, key)
    hit = (j < len(init_key)) & (init_key[np.minimum(j, len(init_key) - 1)] == key)
    assert np.array_equal(pinit, np.where(hit, j, -1))
    assert np.array_equal(pprop, np.where(hit, init_prop[np.minimum(j, len(init_key) - 1)], 3))


def test_helpers_called_with_literals_have_one_signature():
    for helper in (K._edge, K._open_slot, K._rounded_corner, K._stable_argsort):
        assert len(helper.signatures) == 1, helper.__name__


def test_the_engines_bond_mask_is_the_kernels_bond_test():
    """``Engine.bonds`` (Python, for the counts) and ``_is_bond`` (in the kernel) say the same
    thing of every joint model: cohesion or tension > 0."""
    from rockmass.solver import Coulomb, Settings, Stage
    from rockmass.solver.engine import Engine

    from ._models import hand_model, rect

    joints = {"default": Coulomb(1e9, 1e9, 30.0), "glued": Coulomb(1e9, 1e9, 30.0, cohesion_pa=1e5),
              "t": Coulomb(1e9, 1e9, 30.0, tension_pa=1e4),
              "both": Coulomb(1e9, 1e9, 30.0, cohesion_pa=1e5, tension_pa=1e4)}
    eng = Engine(hand_model([rect(0, 0, 1, 1), rect(0, 1, 1, 2)], pairs=[(0, 1)]),
                 Settings(joints=joints, stages=(Stage("s"),)), None)
    rows = np.arange(len(eng.props))
    assert eng.bonds(rows).tolist() == [bool(K._is_bond(eng.props[r])) for r in rows]
    assert eng.bonds(rows).sum() == 3
