"""Seeded disk-network generation: clipped P32 targets, seeding rule, clipped areas, bad input."""

import numpy as np
import pytest

from rockmass.dfn import ConstantSize, ExponentialSize, LognormalSize, PowerLawSize, c13, c23, pole_from_dip
from rockmass.dfn.generation import (BootstrapOrientation, FisherOrientation, FractureSetSpec, IntensityP10,
                                   IntensityP21, IntensityP32, UniformOrientation, generate, realizations,
                                   size_upper_bound)
from rockmass.dfn.network import DiskNetwork

BOX = np.array([[0.0, 0.0, 0.0], [20.0, 15.0, 10.0]])


def fisher_set(p32=1.0, size=None, kappa=20.0, name="J"):
    return FractureSetSpec(FisherOrientation(60.0, 120.0, kappa), size or ConstantSize(1.0),
                           IntensityP32(p32), name=name)


# -- clipped areas -------------------------------------------------------------------------------


def test_disk_inside_has_exact_area_and_disk_outside_none():
    net = DiskNetwork([[5, 5, 5], [50, 5, 5]], [[0.3, 0.2, 0.9]] * 2, [1.5, 1.5], [0, 0], BOX)
    assert net.clipped_area_m2().tolist() == [np.pi * 1.5 ** 2, 0.0]


def test_disk_cut_through_its_centre_keeps_half_its_area():
    # normal along y, the face x = 0 cuts the disk along a diameter: polygon halves are exact
    net = DiskNetwork([[0.0, 5.0, 5.0]], [[0.0, 1.0, 0.0]], [2.0], [0], BOX)
    assert net.clipped_area_m2()[0] == pytest.approx(np.pi * 2.0, rel=1e-12)


@pytest.mark.parametrize("offset", [0.3, 1.0, 1.7])
def test_disk_cut_by_a_face_matches_the_circular_segment(offset):
    # vertical disk (normal along y) with centre `offset` m outside the face x = 0
    r = 2.0
    net = DiskNetwork([[-offset, 5.0, 5.0]], [[0.0, 1.0, 0.0]], [r], [0], BOX)
    segment = r * r * np.arccos(offset / r) - offset * np.sqrt(r * r - offset * offset)
    bound = (2 * np.pi / 64) ** 2 / 6 * np.pi * r * r  # module docstring: error per cut disk
    assert net.clipped_area_m2()[0] == pytest.approx(segment, abs=bound)
    assert net.clipped_area_m2(n_vertices=1024)[0] == pytest.approx(segment, rel=1e-4)


def test_disk_in_a_box_corner_converges_with_polygon_resolution():
    net = DiskNetwork([[0.5, 0.5, 5.0]], [[0.0, 0.0, 1.0]], [2.0], [0], BOX)
    # quarter plane x > 0, y > 0 of a circle centred at (0.5, 0.5): closed form by integration
    r, a = 2.0, 0.5
    x = np.linspace(-a, r, 200001)
    y_top = np.sqrt(np.clip(r * r - x * x, 0, None))
    y_bottom = np.maximum(-a, -y_top)
    exact = np.trapezoid(np.clip(y_top - y_bottom, 0, None), x)
    assert net.clipped_area_m2()[0] == pytest.approx(exact, rel=2e-3)
    assert net.clipped_area_m2(n_vertices=2048)[0] == pytest.approx(exact, rel=1e-5)


# -- P32 targets ---------------------------------------------------------------------------------


@pytest.mark.parametrize("size", [ConstantSize(1.0), PowerLawSize(0.3, 4.0, 2.5), LognormalSize(1.0, 0.5),
                                  ExponentialSize(0.8, r_max_m=5.0)])
def test_achieved_clipped_p32_reaches_target_within_one_disk(size):
    net = generate([fisher_set(0.8, size)], BOX, seed=11)
    volume = np.prod(BOX[1] - BOX[0])
    excess = net.p32() - 0.8
    assert 0.0 <= excess <= np.pi * size_upper_bound(size) ** 2 / volume
    # every disk reaches into the domain
    assert (net.clipped_area_m2() > 0).all()


def test_each_set_reaches_its_own_target():
    sets = [fisher_set(0.5, name="a"), FractureSetSpec(UniformOrientation(), ConstantSize(0.7), IntensityP32(1.2))]
    net = generate(sets, BOX, seed=3)
    assert set(np.unique(net.set_id)) == {0, 1}
    for j, target in enumerate((0.5, 1.2)):
        assert net.p32(j) - target == pytest.approx(0.0, abs=np.pi / np.prod(BOX[1] - BOX[0]) * 1.0001)


def test_p30_is_consistent_with_p32_for_constant_radius():
    # fixed area => count of disk area inside; centres inside ~ P32 / (π r²) (Poisson, 4σ)
    net = generate([fisher_set(2.0, ConstantSize(0.5))], BOX, seed=5)
    expected = 2.0 / (np.pi * 0.25)
    n = expected * np.prod(BOX[1] - BOX[0])
    assert net.p30() == pytest.approx(expected, rel=4 / np.sqrt(n))


def test_p10_and_p21_intensities_convert_with_c13_and_c23():
    o = FisherOrientation(60.0, 120.0, 20.0)
    pole = pole_from_dip(60.0, 120.0)
    spec10 = FractureSetSpec(o, ConstantSize(1.0), IntensityP10(0.5, trend_deg=90.0, plunge_deg=0.0))
    assert spec10.p32 == pytest.approx(0.5 * float(c13([1.0, 0.0, 0.0], pole, 20.0)), rel=1e-12)
    spec21 = FractureSetSpec(o, ConstantSize(1.0), IntensityP21(0.5, dip_deg=90.0, dip_direction_deg=0.0))
    assert spec21.p32 == pytest.approx(0.5 * float(c23(pole_from_dip(90.0, 0.0), pole, 20.0)), rel=1e-12)
    iso = FractureSetSpec(UniformOrientation(), ConstantSize(1.0), IntensityP10(1.0, 0.0, 30.0))
    assert iso.p32 == pytest.approx(2.0, rel=1e-9)


def test_bootstrap_orientation_draws_only_given_poles_and_uses_empirical_c13():
    poles = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    o = BootstrapOrientation(poles)
    normals = o.sample(np.random.default_rng(0), 100)
    assert np.all(np.isclose(np.abs(normals @ poles.T).max(axis=1), 1.0))
    assert o.c13(np.array([0.0, 0.0, 1.0])) == pytest.approx(2.0)  # mean |cos| = 1/2


# -- seeding rule ----------------------------------------------------------------------------------


def _same(a, b):
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("centre_m", "normal", "radius_m", "set_id"))


def test_realization_is_identical_alone_in_batch_or_reversed():
    sets = [fisher_set(0.5), fisher_set(0.3, PowerLawSize(0.5, 3.0, 2.0))]
    alone = generate(sets, BOX, seed=42, realization=3)
    batch = list(realizations(sets, BOX, 42, range(5)))
    reverse = list(realizations(sets, BOX, 42, [4, 3, 2, 1, 0]))
    assert _same(alone, batch[3]) and _same(alone, reverse[1])
    assert not _same(batch[2], batch[3])


def test_adding_a_set_leaves_the_first_set_unchanged():
    one = generate([fisher_set(0.5)], BOX, seed=9, realization=1)
    two = generate([fisher_set(0.5), fisher_set(0.4)], BOX, seed=9, realization=1)
    assert _same(one, two.subset(two.set_id == 0))


def test_generate_does_not_modify_inputs():
    box = BOX.copy()
    generate([fisher_set(0.2)], box, seed=1)
    assert np.array_equal(box, BOX)


# -- bad input -------------------------------------------------------------------------------------


@pytest.mark.parametrize("make, field", [
    (lambda: FisherOrientation(50.0, 270.0, -1.0), "kappa"),
    (lambda: FisherOrientation(95.0, 270.0, 10.0), "dip_deg"),
    (lambda: FisherOrientation(50.0, 400.0, 10.0), "dip_direction_deg"),
    (lambda: PowerLawSize(2.0, 1.0, 2.5), "r_max_m|r_min_m"),
    (lambda: IntensityP32(0.0), "p32"),
    (lambda: IntensityP32(float("nan")), "p32"),
    (lambda: IntensityP10(-1.0, 0.0, 0.0), "p10"),
    (lambda: IntensityP21(1.0, float("nan"), 0.0), "dip_deg"),
])
def test_bad_set_parameters_raise_naming_the_field(make, field):
    with pytest.raises(ValueError, match=field):
        make()


def test_too_many_fractures_raises_naming_the_set_and_count():
    with pytest.raises(ValueError, match=r"sets\[1\] \(big\).*needs about .* fractures.*max_fractures = 1000"):
        generate([fisher_set(0.01), fisher_set(50.0, name="big")], BOX, seed=1, max_fractures=1000)


@pytest.mark.parametrize("kwargs, field", [({"seed": -1}, "seed"), ({"seed": 1, "realization": -2}, "realization")])
def test_bad_seed_or_realization_raises(kwargs, field):
    with pytest.raises(ValueError, match=field):
        generate([fisher_set()], BOX, **kwargs)


def test_bad_domain_raises_naming_the_axis():
    with pytest.raises(ValueError, match="domain_m.*z"):
        generate([fisher_set()], [0, 0, 5, 1, 1, 5], seed=1)
