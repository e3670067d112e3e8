"""Stress: extreme coordinates, sizes and grids give a bounded, correct answer or a clear error."""

import numpy as np
import pytest

from rockmass.fractal import box_count, reference
from tests.fractal._fixtures import random_network


@pytest.mark.parametrize("shift", [1e6, 1e8])
def test_network_far_from_the_origin_keeps_its_dimension(shift):
    seg = random_network(200, seed=21, extent=10.0)
    near = box_count(seg, method="vector", n_offsets=1)
    far = box_count(seg + shift, method="vector", n_offsets=1)
    # at 1e8 m a double resolves ~1e-8 m against 10 m / 360 boxes: a box or two may flip
    assert abs(far.dimension - near.dimension) < 2e-3
    assert np.all(np.abs(far.counts - near.counts) <= np.maximum(2, 1e-3 * near.counts))


@pytest.mark.parametrize("scale", [1e-9, 1e9])
def test_microscopic_and_huge_networks_have_the_same_dimension(scale):
    seg = random_network(200, seed=22, extent=1.0)
    ref = box_count(seg, method="vector", n_offsets=2)
    scaled = box_count(seg * scale, method="vector", n_offsets=2)
    assert np.array_equal(scaled.counts, ref.counts)
    assert np.isfinite(scaled.p21_per_m)


def test_single_short_trace_is_a_line():
    result = box_count(np.array([[0.0, 0.0, 0.01, 0.0]]), n_offsets=4)
    assert result.dimension == pytest.approx(1.0, abs=1e-12)
    assert np.all(np.isfinite(result.offset_dimensions))


def test_collinear_traces_with_gaps_stay_below_1():
    seg = np.array([[0.0, 0.0, 1.0, 0.0], [2.0, 0.0, 3.0, 0.0], [4.0, 0.0, 10.0, 0.0]])
    result = box_count(seg, method="vector")
    assert 0.8 < result.dimension <= 1.0 + 1e-12


def test_smallest_grid_fails_with_a_clear_message():
    with pytest.raises(ValueError, match="box sizes"):
        box_count(reference.straight_line(), grid=4)


def test_grid_above_the_limit_points_to_the_vector_method():
    with pytest.raises(ValueError, match="vector"):
        box_count(reference.straight_line(), grid=100_000)


@pytest.mark.slow
def test_largest_grid_counts_a_line_exactly():
    result = box_count(reference.straight_line(0.0), grid=16384, n_offsets=2)
    assert result.dimension == pytest.approx(1.0, abs=1e-12)


def test_many_offsets_and_near_parallel_dense_traces_are_finite():
    rng = np.random.default_rng(23)
    y = rng.uniform(0, 1, 500)
    seg = np.column_stack([np.zeros(500), y, np.ones(500), y + rng.normal(0, 1e-6, 500)])
    result = box_count(seg, method="vector", n_offsets=64)
    assert np.all(np.isfinite(result.offset_dimensions))
    assert 1.0 <= result.dimension <= 2.0 + 1e-12


def test_dimension_never_exceeds_2_on_a_saturated_network():
    seg = random_network(5000, seed=24, extent=1.0)
    result = box_count(seg, n_offsets=4)
    assert 1.5 < result.dimension <= 2.0 + 1e-12
