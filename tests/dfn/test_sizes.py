"""Size distributions: closed-form moments, sampling statistics, limits, relations and bad input."""

import dataclasses
import math

import numpy as np
import pytest
from scipy import integrate, stats

from rockmass.dfn.sizes import (
    ConstantSize,
    ExponentialSize,
    LognormalSize,
    PowerLawSize,
    mean_trace_length,
    p20_from_p30,
    p30_from_p32,
    p32_from_p30,
    radius_exponent_from_trace,
    trace_exponent_from_radius,
)

POWER_LAWS = [PowerLawSize(0.5, 20.0, alpha) for alpha in (0.0, 0.7, 2.0, 3.5)]
DISTRIBUTIONS = POWER_LAWS + [
    LognormalSize(2.0, 1.5),
    LognormalSize(2.0, 1.5, r_min_m=0.5, r_max_m=6.0),
    ExponentialSize(1.5),
    ExponentialSize(1.5, r_min_m=0.3, r_max_m=4.0),
]


def _reference_power_moment(size, k):
    """docs/fractures.md §10 as printed (valid for α > 0 and k != α)."""
    a, lo, hi = size.alpha, size.r_min_m, size.r_max_m
    return a * lo ** a * (hi ** (k - a) - lo ** (k - a)) / ((1 - (lo / hi) ** a) * (k - a))


def _quad_moment(size, k):
    value, _ = integrate.quad(lambda r: r ** k * float(size.pdf(r)), size.r_min_m, size.r_max_m, epsabs=0,
                              epsrel=1e-11, limit=200)
    return value


@pytest.mark.parametrize("size", POWER_LAWS[1:], ids=lambda s: f"alpha={s.alpha}")
@pytest.mark.parametrize("k", [-1.0, 0.5, 1.0, 2.5, 3.0])  # k = alpha: test_power_law_moment_at_k_equal_to_alpha
def test_power_law_moments_match_the_reference_formula(size, k):
    assert size.moment(k) == pytest.approx(_reference_power_moment(size, k), rel=1e-12)


@pytest.mark.parametrize("size", DISTRIBUTIONS, ids=repr)
@pytest.mark.parametrize("k", [0.0, 1.0, 2.0, 3.0])
def test_moments_match_quadrature_of_the_pdf(size, k):
    assert size.moment(k) == pytest.approx(_quad_moment(size, k), rel=1e-8)


@pytest.mark.parametrize("size", DISTRIBUTIONS, ids=repr)
def test_cdf_is_the_integral_of_the_pdf(size):
    for r in (0.6, 1.0, 3.0, 5.0):
        if size.r_min_m < r < min(size.r_max_m, 200.0):
            value, _ = integrate.quad(lambda x: float(size.pdf(x)), size.r_min_m, r, epsabs=1e-13)
            assert float(size.cdf(r)) == pytest.approx(value, abs=1e-9)


@pytest.mark.parametrize("size", DISTRIBUTIONS, ids=repr)
def test_sample_mean_matches_the_closed_form_within_3_sigma(size):
    n = 200_000
    radii = size.sample(np.random.default_rng(101), n)  # fixed seed
    sigma = math.sqrt(size.moment(2) - size.mean() ** 2)
    assert abs(radii.mean() - size.mean()) < 3 * sigma / math.sqrt(n)
    assert radii.min() >= size.r_min_m and radii.max() <= size.r_max_m


@pytest.mark.parametrize("size", DISTRIBUTIONS, ids=repr)
def test_samples_follow_the_cdf(size):
    radii = size.sample(np.random.default_rng(202), 4000)  # fixed seed
    assert stats.kstest(radii, size.cdf).pvalue > 1e-3


@pytest.mark.parametrize("size", DISTRIBUTIONS, ids=repr)
def test_each_radius_uses_one_uniform_so_a_longer_sample_extends_a_shorter_one(size):
    short = size.sample(np.random.default_rng(8), 10)
    long = size.sample(np.random.default_rng(8), 25)
    np.testing.assert_array_equal(short, long[:10])


def test_power_law_is_continuous_at_alpha_zero():
    log_uniform = PowerLawSize(0.5, 20.0, 0.0)
    for alpha in (1e-14, 1e-10, 1e-7):
        nearly = PowerLawSize(0.5, 20.0, alpha)
        tolerance = 10 * alpha * math.log(40.0) ** 2 + 1e-14
        for k in (-1.0, 0.0, 1.0, 2.0):
            assert nearly.moment(k) == pytest.approx(log_uniform.moment(k), rel=tolerance)
        r = np.array([0.5, 1.0, 7.0, 20.0])
        np.testing.assert_allclose(nearly.pdf(r), log_uniform.pdf(r), rtol=tolerance)
        np.testing.assert_allclose(nearly.cdf(r), log_uniform.cdf(r), rtol=tolerance, atol=1e-15)
        np.testing.assert_allclose(nearly.sample(np.random.default_rng(1), 50),
                                   log_uniform.sample(np.random.default_rng(1), 50), rtol=tolerance)


def test_log_uniform_closed_forms():
    size = PowerLawSize(1.0, math.e ** 2, 0.0)   # Λ = 2
    assert size.moment(1.0) == pytest.approx((math.e ** 2 - 1) / 2, rel=1e-14)
    assert float(size.pdf(3.0)) == pytest.approx(1 / (3.0 * 2.0), rel=1e-14)
    assert float(size.cdf(math.e)) == pytest.approx(0.5, rel=1e-14)


def test_power_law_moment_at_k_equal_to_alpha():
    size = PowerLawSize(0.5, 20.0, 1.5)
    lam = math.log(40.0)
    expected = 1.5 * 0.5 ** 1.5 * lam / (1 - (0.5 / 20.0) ** 1.5)  # the limit k -> α of the formula
    assert size.moment(1.5) == pytest.approx(expected, rel=1e-14)
    for dk in (1e-9, -1e-9):
        assert size.moment(1.5 + dk) == pytest.approx(expected, rel=1e-7)


def test_power_law_with_extreme_parameters_stays_finite():
    steep = PowerLawSize(0.01, 100.0, 500.0)
    radii = steep.sample(np.random.default_rng(0), 10000)
    assert np.isfinite(radii).all() and radii.max() < 0.011  # P(r > 0.011) = (0.01/0.011)^500 ~ 2e-21
    assert math.isfinite(steep.moment(3.0))
    wide = PowerLawSize(1e-200, 1e200, 0.5)
    # Λ = ln 1e400 overflows as a ratio; the moments are then α r_min^k/(α - k) and α r_min^α r_max^(k-α)/(k - α).
    assert wide.moment(0.2) == pytest.approx(0.5 * 1e-40 / 0.3, rel=1e-12)
    assert wide.moment(2.0) == pytest.approx(0.5 * 1e-100 * 1e300 / 1.5, rel=1e-12)
    assert np.isfinite(wide.sample(np.random.default_rng(0), 100)).all()


def test_power_law_density_exponent_and_trace_exponent():
    size = PowerLawSize(0.5, 20.0, 2.5)
    assert size.density_exponent == 3.5
    assert trace_exponent_from_radius(size.density_exponent) == 2.5
    assert radius_exponent_from_trace(trace_exponent_from_radius(4.2)) == pytest.approx(4.2)


def test_lognormal_is_parameterised_by_mean_and_sd():
    size = LognormalSize(mean_m=3.0, sd_m=2.0)
    assert size.mean() == pytest.approx(3.0, rel=1e-14)
    assert size.moment(2) - size.mean() ** 2 == pytest.approx(4.0, rel=1e-12)
    reference = stats.lognorm(s=size._sigma, scale=math.exp(size._mu))
    np.testing.assert_allclose(size.pdf([0.5, 3.0, 9.0]), reference.pdf([0.5, 3.0, 9.0]), rtol=1e-13)


def test_lognormal_truncated_far_in_the_upper_tail_keeps_precision():
    size = LognormalSize(1.0, 0.2, r_min_m=2.0, r_max_m=2.5)
    radii = size.sample(np.random.default_rng(3), 2000)
    assert radii.min() >= 2.0 and radii.max() <= 2.5
    assert radii.mean() == pytest.approx(size.mean(), abs=4 * 0.15 / math.sqrt(2000))


def test_exponential_moments_are_gamma_functions_and_memoryless():
    size = ExponentialSize(2.0)
    for k in (0.5, 1.0, 2.0, 3.0):
        assert size.moment(k) == pytest.approx(2.0 ** k * math.gamma(k + 1), rel=1e-13)
    shifted = ExponentialSize(2.0, r_min_m=5.0)
    assert shifted.mean() == pytest.approx(7.0, rel=1e-13)
    assert shifted.moment(2) == pytest.approx(25 + 2 * 5 * 2 + 8, rel=1e-12)  # E[(5 + T)^2]
    assert math.isfinite(ExponentialSize(1.0, r_min_m=400.0).moment(2.0))


def test_constant_size():
    size = ConstantSize(1.5)
    np.testing.assert_array_equal(size.sample(np.random.default_rng(0), 3), [1.5, 1.5, 1.5])
    assert size.moment(3) == 1.5 ** 3 and size.mean() == 1.5
    np.testing.assert_array_equal(size.cdf([1.0, 1.5, 2.0]), [0.0, 1.0, 1.0])


def test_mean_trace_length_of_equal_disks_is_pi_r_over_2():
    assert mean_trace_length(ConstantSize(2.0)) == pytest.approx(math.pi)


def test_mean_trace_length_matches_simulated_plane_cuts():
    # Statistical oracle: disks cut by a plane are size-biased (accept r with probability r/r_max), the
    # plane meets each at an offset uniform on [0, r], and the chord is 2 sqrt(r² - d²).
    size = PowerLawSize(0.5, 5.0, 1.5)
    rng = np.random.default_rng(404)  # fixed seed
    radii = size.sample(rng, 400_000)
    cut = radii[rng.random(radii.size) < radii / size.r_max_m]
    offsets = rng.random(cut.size) * cut
    chords = 2 * np.sqrt(cut ** 2 - offsets ** 2)
    assert abs(chords.mean() - mean_trace_length(size)) < 3 * chords.std() / math.sqrt(chords.size)


def test_intensity_relations_of_disks():
    size = ConstantSize(1.0)
    assert float(p32_from_p30(2.0, size)) == pytest.approx(2 * math.pi)
    assert float(p30_from_p32(p32_from_p30(0.37, POWER_LAWS[2]), POWER_LAWS[2])) == pytest.approx(0.37)
    # Isotropic disks: E[sin ψ] = π/4, so P20 = P30 · 2E[r] · π/4; and P21 / P20 = mean trace length.
    p20 = float(p20_from_p30(1.0, size, 4 / math.pi))
    assert p20 == pytest.approx(math.pi / 2)
    p21 = float(p32_from_p30(1.0, size)) / (4 / math.pi)
    assert p21 / p20 == pytest.approx(mean_trace_length(size))


def test_distributions_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        POWER_LAWS[0].alpha = 2.0


def test_inputs_are_not_modified():
    r = np.array([0.4, 1.0, 30.0])
    copy = r.copy()
    for size in DISTRIBUTIONS:
        size.pdf(r)
        size.cdf(r)
    np.testing.assert_array_equal(r, copy)


@pytest.mark.parametrize(("call", "match"), [
    (lambda: PowerLawSize(2.0, 2.0, 1.0), "r_max_m"),
    (lambda: PowerLawSize(3.0, 2.0, 1.0), "r_max_m"),
    (lambda: PowerLawSize(0.0, 2.0, 1.0), "r_min_m"),
    (lambda: PowerLawSize(1.0, np.inf, 1.0), "r_max_m must be finite"),
    (lambda: PowerLawSize(1.0, 2.0, -0.5), "alpha"),
    (lambda: PowerLawSize(1.0, 2.0, np.nan), "alpha"),
    (lambda: PowerLawSize(1.0, np.nan, 1.0), "r_max_m"),
    (lambda: ConstantSize(0.0), "radius_m"),
    (lambda: LognormalSize(0.0, 1.0), "mean_m"),
    (lambda: LognormalSize(1.0, -1.0), "sd_m"),
    (lambda: LognormalSize(1.0, 0.1, r_min_m=50.0, r_max_m=60.0), "widen"),
    (lambda: ExponentialSize(-1.0), "scale_m"),
    (lambda: ExponentialSize(1.0, r_min_m=1000.0), "r_min_m"),
    (lambda: ExponentialSize(1.0).moment(-1.0), "k"),
    (lambda: PowerLawSize(1.0, 2.0, 1.0).moment(np.inf), "k"),
    (lambda: PowerLawSize(1.0, 2.0, 1.0).pdf([1.0, np.nan]), "r_m"),
    (lambda: PowerLawSize(1.0, 2.0, 1.0).sample(np.random.default_rng(0), -3), "n must be >= 0"),
    (lambda: trace_exponent_from_radius(0.5), "radius_exponent"),
    (lambda: p32_from_p30(-1.0, ConstantSize(1.0)), "p30"),
    (lambda: p20_from_p30(1.0, ConstantSize(1.0), 0.9), "c23_value"),
])
def test_bad_parameters_name_the_field(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_wrong_types_are_type_errors():
    with pytest.raises(TypeError, match="rng"):
        ConstantSize(1.0).sample(np.random.RandomState(0), 3)
    with pytest.raises(TypeError, match="size"):
        mean_trace_length(2.0)
    with pytest.raises(TypeError, match="alpha"):
        PowerLawSize(1.0, 2.0, "steep")
