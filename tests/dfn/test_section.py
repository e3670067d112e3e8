"""Direct 2D sections: size-biased radii, and the same trace statistics as volume-then-cut."""

import numpy as np
import pytest

from rockmass.dfn import ConstantSize, ExponentialSize, LognormalSize, PowerLawSize, c23
from rockmass.dfn.generation import FisherOrientation, FractureSetSpec, IntensityP32, generate
from rockmass.dfn.sampling import sample_plane
from rockmass.dfn.section import generate_section, size_biased_sample


@pytest.mark.parametrize("size", [PowerLawSize(0.5, 5.0, 2.5), PowerLawSize(0.5, 5.0, 0.5), LognormalSize(1.0, 0.6),
                                  ExponentialSize(0.7), ExponentialSize(0.7, r_min_m=0.2, r_max_m=3.0)])
def test_size_biased_mean_is_second_over_first_moment(size):
    # seed 7 (fixed); E_biased[r] = E[r²]/E[r], σ of the mean from the biased variance E[r³]/E[r] - mean²
    r = size_biased_sample(size, np.random.default_rng(7), 40000)
    mean = size.moment(2.0) / size.moment(1.0)
    sd = np.sqrt(size.moment(3.0) / size.moment(1.0) - mean ** 2)
    assert r.mean() == pytest.approx(mean, abs=4 * sd / np.sqrt(r.size))


def _stats(tm, area):
    lengths = tm.lengths_m()
    return lengths.sum() / area, lengths


SPEC = FractureSetSpec(FisherOrientation(70.0, 150.0, 15.0), ConstantSize(0.6), IntensityP32(1.5))
WINDOW = [(-6.0, -6.0), (6.0, -6.0), (6.0, 6.0), (-6.0, 6.0)]


@pytest.mark.slow
def test_direct_section_matches_volume_then_cut():
    # seeds 101-104 (fixed): 4 realizations each way; the plane x = 10 through a 20 m cube
    point, normal = [10.0, 10.0, 10.0], [1.0, 0.0, 0.0]
    area = 144.0
    direct, volume = [], []
    for i in range(4):
        direct.append(generate_section([SPEC], point, normal, WINDOW, seed=101, realization=i))
        net = generate([SPEC], [0, 0, 0, 20, 20, 20], seed=102, realization=i)
        volume.append(sample_plane(net, point, normal, WINDOW))
    p21_d = sum(_stats(t, area)[0] for t in direct) / 4
    p21_v = sum(_stats(t, area)[0] for t in volume) / 4
    len_d = np.concatenate([t.lengths_m() for t in direct])
    len_v = np.concatenate([t.lengths_m() for t in volume])
    expected = 1.5 / float(c23(normal, SPEC.orientation.mean_pole, 15.0))
    rel = np.sqrt(2.0 / min(len_d.size, len_v.size))  # σ of P21 ≈ sqrt((1 + cv²)/N), cv < 1
    assert p21_d == pytest.approx(expected, rel=3.5 * rel)
    assert p21_v == pytest.approx(expected, rel=3.5 * rel)
    se = np.hypot(len_d.std() / np.sqrt(len_d.size), len_v.std() / np.sqrt(len_v.size))
    assert abs(len_d.mean() - len_v.mean()) < 3.5 * se  # same (window-censored) mean trace length


def test_unclipped_direct_traces_have_mean_length_pi_r_over_2():
    # seed 5 (fixed): midpoints in the inner 10 m x 10 m, window grown by r so none is clipped
    tm = generate_section([SPEC], [0, 0, 0], [0.0, 0.6, 0.8], [(-5.6, -5.6), (5.6, -5.6), (5.6, 5.6), (-5.6, 5.6)],
                          seed=5)
    mid = tm.xy_m.reshape(-1, 2, 2).mean(axis=1)
    lengths = tm.lengths_m()[np.all(np.abs(mid) <= 5.0, axis=1)]
    sigma = 0.6 * np.sqrt(8 / 3 - np.pi ** 2 / 4) / np.sqrt(lengths.size)
    assert lengths.mean() == pytest.approx(np.pi * 0.6 / 2, abs=3.5 * sigma)


def test_section_is_reproducible_and_realizations_differ():
    a = generate_section([SPEC], [0, 0, 0], [0, 0, 1], WINDOW, seed=3, realization=2)
    b = generate_section([SPEC], [0, 0, 0], [0, 0, 1], WINDOW, seed=3, realization=2)
    c = generate_section([SPEC], [0, 0, 0], [0, 0, 1], WINDOW, seed=3, realization=1)
    assert np.array_equal(a.xy_m, b.xy_m) and not np.array_equal(a.xy_m, c.xy_m)
    assert a.frame == "plane" and set(a.attributes) >= {"set", "disk"}


def test_section_guard_names_the_set():
    with pytest.raises(ValueError, match=r"sets\[0\].*max_fractures = 10"):
        generate_section([SPEC], [0, 0, 0], [0, 0, 1], WINDOW, seed=1, max_fractures=10)
