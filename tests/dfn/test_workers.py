"""Realization i is the same network whatever the number of workers, the chunking or the order (docs/design.md §3.5).

Oracle: byte equality of every array against realization i generated alone in this process.
Workers are separate interpreters (multiprocessing "spawn"), so no state is shared with the parent.
"""

import multiprocessing
from concurrent.futures import ProcessPoolExecutor

import pytest
from rockmass.dfn.generation import (
    FisherOrientation,
    FractureSetSpec,
    IntensityP32,
    generate,
    realizations,
)
from rockmass.dfn.sizes import LognormalSize, PowerLawSize

SPECS = [FractureSetSpec(FisherOrientation(50, 270, 20), PowerLawSize(0.5, 5.0, 2.5), IntensityP32(0.6)),
         FractureSetSpec(FisherOrientation(80, 10, 5), LognormalSize(1.0, 0.5), IntensityP32(0.4))]
DOMAIN = [0, 0, 0, 12, 10, 8]
SEED = 2026
N = 10


def _arrays(net):
    return (net.centre_m, net.normal, net.radius_m, net.set_id)


def _chunk(indices):
    """Worker: a chunk of realizations, as arrays (pickled back to the parent)."""
    return [(i, _arrays(net)) for i, net in zip(indices, realizations(SPECS, DOMAIN, SEED, indices))]


def _same(a, b):
    return all(x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes() for x, y in zip(a, b))


@pytest.fixture(scope="module")
def alone():
    return {i: _arrays(generate(SPECS, DOMAIN, seed=SEED, realization=i)) for i in range(N)}


@pytest.mark.parametrize("workers, chunks", [(2, [[0, 2, 4, 6, 8], [9, 7, 5, 3, 1]]),
                                             (3, [[7], [3, 8, 0], [1, 2], [9, 6, 5, 4]])])
def test_realizations_are_identical_for_any_number_of_workers_and_chunks(alone, workers, chunks):
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        results = [item for part in pool.map(_chunk, chunks) for item in part]
    assert sorted(i for i, _ in results) == list(range(N))
    for i, arrays in results:
        assert _same(arrays, alone[i]), f"realization {i} differs with {workers} workers"


def test_realization_7_alone_equals_7_of_a_batch_and_differs_from_its_neighbours(alone):
    batch = dict(_chunk(list(range(N))))
    assert _same(batch[7], alone[7])
    assert not _same(alone[7], alone[6]) and not _same(alone[7], alone[8])
