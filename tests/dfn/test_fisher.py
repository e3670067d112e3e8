"""Fisher distribution: sampler stability and statistics, density/CDF identities, tensor fit, cones."""

import math

import numpy as np
import pytest
from scipy import integrate, stats

from rockmass.dfn.fisher import (
    confidence_cone,
    fisher_angle_cdf,
    fisher_angle_pdf,
    fisher_density,
    fit_fisher,
    orientation_tensor,
    sample_fisher,
    variability_cone,
)
from rockmass.dfn.orientation import angle_between, pole_from_dip, to_lower_hemisphere

OBLIQUE = pole_from_dip(35.0, 120.0)
MEANS = {"down": [0.0, 0.0, -1.0], "up": [0.0, 0.0, 1.0], "oblique": OBLIQUE, "horizontal": [1.0, 0.0, 0.0]}
KAPPAS = [0.0, 1e-12, 1e-6, 1e-3, 1.0, 5.0, 50.0, 700.0, 1000.0, 1e4, 1e8]


def _mean_cos(kappa):
    """E[cos θ] = coth κ - 1/κ (Fisher 1953), by its series where the closed form cancels."""
    if kappa < 1e-3:
        return kappa / 3.0 - kappa ** 3 / 45.0
    return 1.0 / math.tanh(kappa) - 1.0 / kappa


def _sd_cos(kappa):
    """sd of cos θ: 1 - cos θ is exponential with rate κ truncated to [0, 2], Var = 1/κ² - 1/sinh²κ."""
    if kappa < 0.1:
        return math.sqrt(1.0 / 3.0)  # the uniform value, an upper bound here
    inv_sinh_sq = 4.0 * math.exp(-2.0 * kappa) / (-math.expm1(-2.0 * kappa)) ** 2
    return math.sqrt(1.0 / kappa ** 2 - inv_sinh_sq)


@pytest.mark.parametrize("kappa", KAPPAS)
@pytest.mark.parametrize("mean", list(MEANS))
def test_fisher_sampler_gives_finite_unit_vectors_for_every_kappa(kappa, mean):
    vectors = sample_fisher(np.random.default_rng(1), MEANS[mean], kappa, 2000)  # seed 1: arbitrary
    assert vectors.shape == (2000, 3)
    assert np.isfinite(vectors).all()
    np.testing.assert_allclose(np.linalg.norm(vectors, axis=1), 1.0, atol=1e-15)


@pytest.mark.parametrize("kappa", KAPPAS)
def test_fisher_sampler_mean_cosine_is_coth_kappa_minus_one_over_kappa(kappa):
    n = 20000
    vectors = sample_fisher(np.random.default_rng(20240601), OBLIQUE, kappa, n)  # fixed seed
    cos_theta = vectors @ OBLIQUE
    tolerance = 4.0 * _sd_cos(kappa) / math.sqrt(n) + 1e-15
    assert abs(cos_theta.mean() - _mean_cos(kappa)) < tolerance


@pytest.mark.parametrize("kappa", [0.0, 1e-6, 5.0, 50.0, 1000.0])
def test_sampled_angles_follow_the_fisher_angle_cdf(kappa):
    vectors = sample_fisher(np.random.default_rng(7), [0.0, 0.0, -1.0], kappa, 5000)  # seed 7: arbitrary
    theta = angle_between(vectors, [0.0, 0.0, -1.0], axial=False)
    result = stats.kstest(theta, lambda t: fisher_angle_cdf(t, kappa))
    assert result.pvalue > 1e-3


@pytest.mark.parametrize("mean", ["down", "up", "oblique"])
def test_sampled_azimuth_about_the_mean_is_uniform(mean):
    axis = np.asarray(MEANS[mean], dtype=float)
    vectors = sample_fisher(np.random.default_rng(11), axis, 5.0, 5000)  # seed 11: arbitrary
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    phi = np.mod(np.arctan2(vectors @ e2, vectors @ e1), 2 * np.pi)
    assert stats.kstest(phi, stats.uniform(0.0, 2 * np.pi).cdf).pvalue > 1e-3


@pytest.mark.parametrize("mean", list(MEANS))
def test_sample_mean_direction_lies_within_its_confidence_cone(mean):
    vectors = sample_fisher(np.random.default_rng(3), MEANS[mean], 30.0, 3000)  # seed 3: arbitrary
    resultant = vectors.sum(axis=0)
    cone = confidence_cone(3000, float(np.linalg.norm(resultant)), confidence=0.999)
    assert float(angle_between(resultant, MEANS[mean], axial=False)) < cone


def test_sampler_is_reproducible_and_takes_two_uniforms_per_vector():
    a = sample_fisher(np.random.default_rng(5), OBLIQUE, 20.0, 100)
    b = sample_fisher(np.random.default_rng(5), OBLIQUE, 20.0, 100)
    np.testing.assert_array_equal(a, b)
    rng = np.random.default_rng(5)
    sample_fisher(rng, OBLIQUE, 20.0, 100)
    reference = np.random.default_rng(5)
    reference.random(200)
    assert rng.random() == reference.random()


def test_huge_kappa_puts_every_vector_on_the_mean():
    for axis in ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], OBLIQUE):
        vectors = sample_fisher(np.random.default_rng(0), axis, 1e12, 100)
        assert float(angle_between(vectors, axis, axial=False).max()) < 1e-3


def test_fisher_density_integrates_to_one_over_the_sphere():
    for kappa in (0.0, 1.0, 100.0, 1e4):
        cone = float(variability_cone(kappa, 1.0 - 1e-15))
        total, _ = integrate.quad(lambda t: float(fisher_angle_pdf(t, kappa)), 0.0, cone,
                                  points=[min(cone / 2, 3.0 * math.degrees(1 / math.sqrt(kappa + 1e-300)))],
                                  epsabs=1e-13, limit=200)
        assert total == pytest.approx(1.0, abs=1e-9)


def test_angle_pdf_is_the_derivative_of_the_cdf():
    theta = np.array([0.5, 5.0, 20.0, 60.0, 120.0, 179.0])
    h = 1e-5
    for kappa in (0.0, 0.3, 7.0, 60.0):
        slope = (fisher_angle_cdf(theta + h, kappa) - fisher_angle_cdf(theta - h, kappa)) / (2 * h)
        np.testing.assert_allclose(fisher_angle_pdf(theta, kappa), slope, rtol=1e-6, atol=1e-10)  # cdf rounding / h


def test_density_per_steradian_matches_the_angle_density():
    theta = np.radians(np.array([1.0, 10.0, 45.0, 100.0]))
    vectors = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    for kappa in (0.0, 2.0, 300.0):
        per_degree = fisher_density(vectors, [0.0, 0.0, 1.0], kappa) * 2 * np.pi * np.sin(theta) * np.pi / 180
        np.testing.assert_allclose(per_degree, fisher_angle_pdf(np.degrees(theta), kappa), rtol=1e-12)


def test_uniform_density_is_one_over_four_pi():
    assert float(fisher_density([1.0, 2.0, 3.0], [0.0, 0.0, 1.0], 0.0)) == pytest.approx(1 / (4 * np.pi))


def test_huge_kappa_density_and_cdf_do_not_overflow():
    assert np.isfinite(fisher_density([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 1e300))
    assert float(fisher_angle_cdf(0.001, 1e8)) == pytest.approx(-math.expm1(-1e8 * 2 * math.sin(math.radians(0.0005)) ** 2))


@pytest.mark.parametrize("kappa", [0.0, 1e-9, 0.5, 10.0, 1e3, 1e7])
def test_variability_cone_inverts_the_angle_cdf(kappa):
    for coverage in (0.0, 0.1, 0.63, 0.95, 0.999):
        theta = variability_cone(kappa, coverage)
        assert float(fisher_angle_cdf(theta, kappa)) == pytest.approx(coverage, abs=1e-9)


def test_variability_cone_of_uniform_poles_is_closed_form():
    # κ = 0: 1 - cos θ = 2q.
    assert float(variability_cone(0.0, 0.25)) == pytest.approx(60.0, abs=1e-12)
    assert float(variability_cone(0.0, 1.0)) == pytest.approx(180.0, abs=1e-12)


def test_confidence_cone_follows_fisher_1953():
    n, r = 10, 9.5
    expected = math.degrees(math.acos(1.0 - (n - r) / r * (20.0 ** (1.0 / (n - 1)) - 1.0)))
    assert confidence_cone(n, r) == pytest.approx(expected, rel=1e-12)
    assert confidence_cone(2, 0.1) == 180.0  # too scattered to bound the mean


def test_orientation_tensor_has_unit_trace_and_ignores_the_sign_of_poles():
    poles = sample_fisher(np.random.default_rng(2), OBLIQUE, 10.0, 50)
    signs = np.where(np.arange(50) % 2 == 0, 1.0, -1.0)[:, None]
    tensor = orientation_tensor(poles)
    assert np.trace(tensor) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(orientation_tensor(poles * signs), tensor, atol=1e-15)
    np.testing.assert_allclose(tensor, tensor.T, atol=0)


def test_tensor_mean_of_a_subvertical_set_dipping_both_ways():
    # Poles about East (a N-S striking vertical set); folded to the lower hemisphere, they fall on both
    # sides of the stereonet (trends near 90 and 270), so their plain vector mean is meaningless.
    poles = to_lower_hemisphere(sample_fisher(np.random.default_rng(17), [1.0, 0.0, 0.0], 40.0, 400))
    assert (poles[:, 0] > 0).any() and (poles[:, 0] < 0).any()
    fit = fit_fisher(poles)
    assert float(angle_between(fit.mean_pole, [1.0, 0.0, 0.0])) < fit.alpha95_deg
    assert fit.mean_dip_deg > 85.0
    assert fit.mean_pole[2] <= 0.0
    assert abs(fit.kappa - 40.0) < 3 * 40.0 / math.sqrt(399)
    np.testing.assert_array_less(-1e-12, fit.poles @ fit.mean_pole)  # flipped to the mean's side


@pytest.mark.parametrize("kappa", [5.0, 20.0, 200.0])
def test_kappa_estimate_recovers_kappa_within_3_sigma(kappa):
    # For κ not small 2κ(N - R) ~ χ²(2N - 2), so κ̂ = (N - 1)/(N - R) has relative sd ≈ 1/sqrt(N - 1).
    n = 4000
    poles = sample_fisher(np.random.default_rng(int(kappa)), OBLIQUE, kappa, n)  # seed = κ: fixed
    fit = fit_fisher(poles)
    assert abs(fit.kappa - kappa) < 3.0 * kappa / math.sqrt(n - 1)
    assert float(angle_between(fit.mean_pole, OBLIQUE)) < fit.alpha95_deg * 1.5


def test_kappa_of_identical_poles_is_finite_and_set_by_the_resolution():
    poles = np.tile(OBLIQUE, (10, 1))
    fit = fit_fisher(poles, resolution_deg=1.0)
    assert fit.kappa == pytest.approx(9.0 / (10.0 * (1.0 - math.cos(math.radians(1.0)))), rel=1e-12)
    assert math.isfinite(fit.alpha95_deg) and fit.alpha95_deg == pytest.approx(0.0, abs=1e-6)


def test_kappa_of_two_poles_is_one_over_two_minus_r():
    half = math.radians(20.0)
    poles = [[math.sin(half), 0.0, -math.cos(half)], [-math.sin(half), 0.0, -math.cos(half)]]
    fit = fit_fisher(poles)
    assert fit.kappa == pytest.approx(1.0 / (2.0 - 2.0 * math.cos(half)), rel=1e-12)
    np.testing.assert_allclose(fit.mean_pole, [0.0, 0.0, -1.0], atol=1e-15)


def test_tight_set_keeps_kappa_precision():
    # N - R ~ 1e-10 would lose all digits as N - |Σn|; the spread form keeps them.
    poles = sample_fisher(np.random.default_rng(23), OBLIQUE, 1e9, 1000)
    fit = fit_fisher(poles, resolution_deg=1e-6)
    assert abs(fit.kappa - 1e9) < 4 * 1e9 / math.sqrt(999)


def test_fit_reports_eigenvalues_in_descending_order_summing_to_one():
    fit = fit_fisher(sample_fisher(np.random.default_rng(4), OBLIQUE, 10.0, 200))
    assert fit.eigenvalues[0] >= fit.eigenvalues[1] >= fit.eigenvalues[2]
    assert fit.eigenvalues.sum() == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_array_equal(fit.eigenvectors[:, 0], fit.mean_pole)
    assert fit.variability_63_deg < fit.variability_95_deg


def test_inputs_are_not_modified():
    poles = sample_fisher(np.random.default_rng(9), OBLIQUE, 10.0, 20) * 3.0
    mean = np.array([0.0, 0.0, -2.0])
    copies = poles.copy(), mean.copy()
    fit_fisher(poles)
    orientation_tensor(poles)
    fisher_density(poles, mean, 3.0)
    sample_fisher(np.random.default_rng(0), mean, 3.0, 5)
    np.testing.assert_array_equal(poles, copies[0])
    np.testing.assert_array_equal(mean, copies[1])


@pytest.mark.parametrize(("call", "match"), [
    (lambda: sample_fisher(np.random.default_rng(0), [0, 0, 1], -1.0, 5), "kappa"),
    (lambda: sample_fisher(np.random.default_rng(0), [0, 0, 1], np.nan, 5), "kappa"),
    (lambda: sample_fisher(np.random.default_rng(0), [0, 0, 0], 1.0, 5), "mean_pole"),
    (lambda: sample_fisher(np.random.default_rng(0), [[0, 0, 1]] * 2, 1.0, 5), "mean_pole"),
    (lambda: sample_fisher(np.random.default_rng(0), [0, 0, 1], 1.0, -1), "n must be >= 0"),
    (lambda: fit_fisher([[0.0, 0.0, 1.0]]), "at least 2"),
    (lambda: fit_fisher([[0.0, 0.0, 1.0], [np.nan, 0.0, 1.0]]), "poles must be finite"),
    (lambda: fit_fisher([[0, 0, 1], [0, 1, 1]], resolution_deg=0.0), "resolution_deg"),
    (lambda: variability_cone(1.0, 1.5), "coverage"),
    (lambda: variability_cone(-2.0), "kappa"),
    (lambda: fisher_angle_cdf(181.0, 1.0), "theta_deg"),
    (lambda: fisher_angle_pdf(10.0, -1.0), "kappa"),
    (lambda: confidence_cone(1, 1.0), "n must be >= 2"),
    (lambda: confidence_cone(5, 6.0), "resultant_length"),
    (lambda: confidence_cone(5, 4.0, confidence=1.0), "confidence"),
])
def test_bad_input_names_the_field(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_wrong_types_are_type_errors():
    with pytest.raises(TypeError, match="rng"):
        sample_fisher(np.random.RandomState(0), [0, 0, 1], 1.0, 5)
    with pytest.raises(TypeError, match="n must be an integer"):
        sample_fisher(np.random.default_rng(0), [0, 0, 1], 1.0, 5.0)
