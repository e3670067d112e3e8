"""Virtual sampling: scanline hits (Poisson, P10 = P32/C13), plane traces (P21 = P32/C23), frames."""

import numpy as np
import pytest
import shapely
from scipy import stats

from rockmass.dfn import ConstantSize, c13, c23
from rockmass.dfn.generation import FisherOrientation, FractureSetSpec, IntensityP32, generate
from rockmass.dfn.network import DiskNetwork
from rockmass.dfn.sampling import plane_frame, sample_line, sample_plane

BOX = [-10.0, -10.0, -10.0, 10.0, 10.0, 10.0]


def test_hand_drawn_scanline_hits_sorted_with_sets_and_spacings():
    net = DiskNetwork([[0, 0, 3], [0, 0, 1], [0.5, 0, 2], [5, 5, 2]], [[0, 0, 1], [0, 0, 1], [1, 0, 1], [0, 0, 1]],
                      [1.0, 1.0, 1.0, 1.0], [1, 0, 2, 0], BOX)
    hits = sample_line(net, [0, 0, 0], [0, 0, 4])
    assert hits.position_m.tolist() == pytest.approx([1.0, 2.5, 3.0])
    assert hits.set_id.tolist() == [0, 2, 1] and hits.disk_index.tolist() == [1, 2, 0]
    assert hits.p10() == 0.75 and hits.p10(0) == 0.25
    assert hits.spacings_m().tolist() == pytest.approx([1.5, 0.5])


def test_scanline_parallel_to_disk_or_past_its_rim_misses():
    net = DiskNetwork([[0, 0, 0], [0, 2.0, 1]], [[1, 0, 0], [0, 0, 1]], [1.0, 1.0], [0, 0], BOX)
    assert sample_line(net, [0, 0, -1], [0, 0, 1]).n_hits == 0 + 0  # in-plane line: denom 0 is a miss
    assert sample_line(net, [0, 0, 0.5], [0, 0, 2]).n_hits == 0


@pytest.fixture(scope="module")
def network():
    # seed 20261121 (fixed): Fisher set, constant radius 0.5 m, P32 = 2 m²/m³ in a 24 m cube, ~1.2e5 disks
    spec = FractureSetSpec(FisherOrientation(60.0, 120.0, 10.0), ConstantSize(0.5), IntensityP32(2.0))
    return spec, generate([spec], [0, 0, 0, 24, 24, 24], seed=20261121)


@pytest.mark.slow
def test_scanline_hits_are_poisson_with_p10_equal_p32_over_c13(network):
    spec, net = network
    direction = np.array([1.0, 0.0, 0.0])
    p10 = 2.0 / float(c13(direction, spec.orientation.mean_pole, 10.0))
    counts, spacings = [], []
    for y in np.arange(1.5, 23, 2.0):          # 11 x 11 parallel lines, 2 m apart (> 2r: independent)
        for z in np.arange(1.5, 23, 2.0):
            hits = sample_line(net, [0, y, z], [24, y, z])
            counts.append(hits.n_hits)
            spacings.append(hits.spacings_m())
    counts = np.array(counts)
    expected = p10 * 24.0 * counts.size
    assert abs(counts.sum() - expected) < 3.0 * np.sqrt(expected)  # Poisson: σ = sqrt(N)
    dispersion = counts.var(ddof=1) / counts.mean()                 # 1 for Poisson, σ ≈ sqrt(2/(k-1))
    assert abs(dispersion - 1.0) < 4.0 * np.sqrt(2.0 / (counts.size - 1))
    gaps = np.concatenate(spacings)
    assert stats.kstest(gaps, "expon", args=(0, 1.0 / p10)).pvalue > 1e-3  # exponential spacings


@pytest.mark.parametrize("normal", [[1.0, 0.0, 0.0], [0.3, -0.5, 0.8]])
def test_plane_traces_have_p21_equal_p32_over_c23(network, normal):
    spec, net = network
    half = 10.0
    window = [(-half, -half), (half, -half), (half, half), (-half, half)]
    tm = sample_plane(net, [12, 12, 12], normal, window)
    lengths = tm.lengths_m()
    p21 = lengths.sum() / (2 * half) ** 2
    expected = 2.0 / float(c23(normal, spec.orientation.mean_pole, 10.0))
    # relative σ of a sum of N random lengths: sqrt((1 + cv²) / N)
    rel_sigma = np.sqrt((1 + (lengths.std() / lengths.mean()) ** 2) / lengths.size)
    assert p21 == pytest.approx(expected, rel=3.5 * rel_sigma)
    assert tm.attributes["set"].tolist() == [0] * tm.n_traces


def test_mean_trace_length_is_pi_r_over_2_for_constant_radius(network):
    _, net = network
    # select traces by chord midpoint in an inner window (independent of length), window grown by r so
    # that none of them is clipped
    tm = sample_plane(net, [12, 12, 12], [0.0, 1.0, 0.2], [(-11, -11), (11, -11), (11, 11), (-11, 11)])
    ends = tm.xy_m.reshape(-1, 2, 2)
    mid = ends.mean(axis=1)
    inner = np.all(np.abs(mid) <= 10.0, axis=1)
    lengths = tm.lengths_m()[inner]
    # chords of radius r with uniform offset: mean πr/2, variance r²(8/3 - π²/4)
    sigma = 0.5 * np.sqrt(8 / 3 - np.pi ** 2 / 4) / np.sqrt(lengths.size)
    assert lengths.mean() == pytest.approx(np.pi * 0.5 / 2, abs=3.5 * sigma)


def test_convex_clipping_agrees_with_shapely(network):
    _, net = network
    window = np.array([(-3.0, -2.0), (4.0, -3.0), (5.0, 3.0), (0.0, 5.0), (-4.0, 2.0)])
    big = sample_plane(net, [12, 12, 12], [0.2, 0.9, 0.1], [(-20, -20), (20, -20), (20, 20), (-20, 20)])
    clipped = sample_plane(net, [12, 12, 12], [0.2, 0.9, 0.1], window)
    reference = shapely.length(shapely.intersection(big.to_shapely(), shapely.Polygon(window))).sum()
    assert clipped.total_length_m() == pytest.approx(reference, rel=1e-12)


def test_non_convex_window_keeps_only_pieces_inside(network):
    _, net = network
    window = shapely.Polygon([(-8, -8), (8, -8), (8, 8), (0, 0), (-8, 8)])
    big = sample_plane(net, [12, 12, 12], [1.0, 0.0, 0.0], [(-20, -20), (20, -20), (20, 20), (-20, 20)])
    tm = sample_plane(net, [12, 12, 12], [1.0, 0.0, 0.0], window)
    assert tm.total_length_m() == pytest.approx(
        shapely.length(shapely.intersection(big.to_shapely(), window)).sum(), rel=1e-12)
    assert shapely.covers(window.buffer(1e-9), tm.to_shapely()).all()


def test_plane_frame_is_right_handed_with_u_horizontal():
    for normal in ([0.0, 1.0, 0.0], [0.3, -0.5, 0.8], [0, 0, 1], [0, 0, -1]):
        u, v, m = plane_frame(normal)
        assert np.allclose(np.cross(u, v), m) and abs(u @ v) < 1e-15
    u, v, _ = plane_frame([0.0, 0.0, 1.0])
    assert u.tolist() == [1, 0, 0] and v.tolist() == [0, 1, 0]            # map view
    u, v, _ = plane_frame([1.0, 0.0, 0.0])                                  # face looking East
    assert u.tolist() == pytest.approx([0, 1, 0]) and v.tolist() == pytest.approx([0, 0, 1])


def test_vertical_disk_on_horizontal_plane_gives_its_diameter():
    net = DiskNetwork([[1.0, 2.0, 0.0]], [[0.0, 1.0, 0.0]], [1.5], [3], BOX)
    tm = sample_plane(net, [0, 0, 0], [0, 0, 1], [(-5, -5), (5, -5), (5, 5), (-5, 5)])
    assert tm.lengths_m().tolist() == pytest.approx([3.0])
    assert sorted(tm.xy_m[:, 0].tolist()) == pytest.approx([-0.5, 2.5]) and tm.attributes["set"].tolist() == [3]


@pytest.mark.parametrize("call, match", [
    (lambda n: sample_line(n, [0, 0, 0], [0, 0, 0]), "zero length"),
    (lambda n: sample_line(n, [0, 0], [0, 0, 1]), "start"),
    (lambda n: sample_plane(n, [0, 0, 0], [0, 0, 0], [(0, 0), (1, 0), (0, 1)]), "normal"),
    (lambda n: sample_plane(n, [0, 0, 0], [0, 0, 1], [(0, 0), (1, 0)]), "window_uv_m"),
    (lambda n: sample_plane(n, [0, 0, float("nan")], [0, 0, 1], [(0, 0), (1, 0), (0, 1)]), "point"),
])
def test_bad_sampling_input_raises_naming_the_argument(call, match):
    net = DiskNetwork([[0, 0, 0]], [[0, 0, 1]], [1.0], [0], BOX)
    with pytest.raises(ValueError, match=match):
        call(net)
