"""Stereology: C13/C23 against check values, closed forms and independent quadratures; the P32 solve."""

import math

import numpy as np
import pytest
from scipy import integrate
from scipy.special import i1e

from rockmass.dfn.fisher import sample_fisher
from rockmass.dfn.orientation import angle_between, pole_from_dip, vector_from_trend_plunge
from rockmass.dfn.stereology import (
    C13_ISOTROPIC,
    C23_ISOTROPIC,
    c13,
    c13_from_angle,
    c23,
    c23_from_angle,
    p10_from_p32,
    p21_from_p32,
    p32_from_p10,
    p32_from_p21,
    solve_p32,
    terzaghi_weights,
)

# docs/fractures.md §7 check values: (kappa, angle between line or plane normal and the mean pole) -> C.
C13_CHECK = [(10, 0, 1.111), (10, 30, 1.283), (10, 60, 2.145), (10, 90, 4.123), (50, 0, 1.020), (50, 90, 8.930)]
C23_CHECK = [(10, 0, 2.625), (10, 30, 1.776), (10, 60, 1.191), (10, 90, 1.051), (50, 0, 5.685), (50, 90, 1.010)]
KAPPAS = [1e-6, 1e-3, 0.1, 1.0, 10.0, 50.0, 1e3, 1e5, 1e8]


def _one_minus_exp(x):
    return -math.expm1(-x)


def _mean_abs_cos_along_mean(kappa):
    """β = 0: E|cos θ| = κ/(2 sinh κ) ∫|x| e^(κx) dx over [-1, 1], in an overflow-free form."""
    upper = (kappa - 1.0 + math.exp(-kappa)) / kappa ** 2           # e^-κ ∫_0^1 x e^(κx) dx
    lower = (math.exp(-kappa) - math.exp(-2 * kappa) * (kappa + 1.0)) / kappa ** 2
    return kappa * (upper + lower) / _one_minus_exp(2 * kappa)


def _mean_sin_along_mean(kappa):
    """β = 0: E[sin θ] = π i1e(κ)/(1 - e^(-2κ)) (∫ sin²θ e^(κ cos θ) dθ = π I1(κ)/κ)."""
    return math.pi * i1e(kappa) / _one_minus_exp(2 * kappa)


def _c13_oracle(beta_deg, kappa):
    """Independent route: integrate over θ about the mean with the azimuth average in closed form,
    E_φ|a + b cos φ| = |a| if |a| >= |b| else (2/π)(sqrt(b² - a²) + a asin(a/|b|))."""
    beta = math.radians(beta_deg)

    def density(theta):
        return math.exp(-2 * kappa * math.sin(theta / 2) ** 2) * math.sin(theta)

    def integrand(theta):
        a = math.cos(theta) * math.cos(beta)
        b = abs(math.sin(theta) * math.sin(beta))
        g = abs(a) if abs(a) >= b else 2 / math.pi * (math.sqrt(b * b - a * a) + a * math.asin(a / b))
        return g * density(theta)

    top = min(math.pi, 2 * math.asin(min(1.0, math.sqrt(30.0 / kappa))))
    kinks = [p for p in (math.pi / 2 - beta, math.pi / 2 + beta) if 0 < p < top] or None
    value, _ = integrate.quad(integrand, 0.0, top, points=kinks, epsabs=0, epsrel=1e-12, limit=200)
    norm, _ = integrate.quad(density, 0.0, top, epsabs=0, epsrel=1e-12, limit=200)
    return norm / value


def _c23_oracle(beta_deg, kappa, n=200):
    """Independent route: tensor Gauss-Legendre over (θ, φ) about the mean, sin ψ evaluated directly."""
    beta = math.radians(beta_deg)
    x, w = np.polynomial.legendre.leggauss(n)
    top = min(math.pi, 2 * math.asin(min(1.0, math.sqrt(30.0 / kappa))))
    edges = sorted({0.0, min(beta, top), top})
    theta = np.concatenate([(lo + hi) / 2 + (hi - lo) / 2 * x for lo, hi in zip(edges[:-1], edges[1:])])
    w_theta = np.concatenate([(hi - lo) / 2 * w for lo, hi in zip(edges[:-1], edges[1:])])
    phi, w_phi = math.pi / 2 * (x + 1), math.pi / 2 * w  # [0, π] by symmetry
    t, p = np.meshgrid(theta, phi, indexing="ij")
    cos_psi = np.sin(t) * np.cos(p) * math.sin(beta) + np.cos(t) * math.cos(beta)
    weight = np.exp(-2 * kappa * np.sin(t / 2) ** 2) * np.sin(t) * w_theta[:, None] * w_phi
    return weight.sum() / (np.sqrt(np.clip(1 - cos_psi ** 2, 0, None)) * weight).sum()


@pytest.mark.parametrize(("kappa", "angle", "expected"), C13_CHECK)
def test_c13_matches_reference_check_values(kappa, angle, expected):
    value = float(c13_from_angle(angle, kappa))
    assert round(value, 3) == expected and abs(value - expected) < 1e-3


@pytest.mark.parametrize(("kappa", "angle", "expected"), C23_CHECK)
def test_c23_matches_reference_check_values(kappa, angle, expected):
    value = float(c23_from_angle(angle, kappa))
    assert round(value, 3) == expected and abs(value - expected) < 1e-3


def test_isotropic_constants_are_exactly_2_and_4_over_pi():
    angles = np.linspace(0.0, 180.0, 7)
    np.testing.assert_array_equal(c13_from_angle(angles, 0.0), 2.0)
    np.testing.assert_array_equal(c23_from_angle(angles, 0.0), 4.0 / math.pi)
    assert C13_ISOTROPIC == 2.0 and C23_ISOTROPIC == 4.0 / math.pi
    assert float(c13([0.3, 0.4, 0.5])) == 2.0 and float(c23([0.3, 0.4, 0.5])) == 4.0 / math.pi


def test_small_kappa_tends_to_the_isotropic_constants():
    for angle in (0.0, 45.0, 90.0):
        assert float(c13_from_angle(angle, 1e-9)) == pytest.approx(2.0, rel=1e-8)
        assert float(c23_from_angle(angle, 1e-9)) == pytest.approx(4.0 / math.pi, rel=1e-8)


@pytest.mark.parametrize("kappa", KAPPAS)
def test_constants_match_closed_forms_along_and_across_the_mean(kappa):
    e_abs_cos_across = 2.0 * i1e(kappa) / _one_minus_exp(2 * kappa)   # β = 90°: (2/π) E[sin θ]
    assert float(c13_from_angle(90.0, kappa)) == pytest.approx(1.0 / e_abs_cos_across, rel=1e-9)
    assert float(c23_from_angle(0.0, kappa)) == pytest.approx(1.0 / _mean_sin_along_mean(kappa), rel=1e-9)
    if kappa >= 0.1:  # the closed form itself cancels below
        assert float(c13_from_angle(0.0, kappa)) == pytest.approx(1.0 / _mean_abs_cos_along_mean(kappa), rel=1e-9)


@pytest.mark.parametrize("kappa", [0.5, 5.0, 50.0, 5e3, 1e7])
@pytest.mark.parametrize("angle", [5.0, 30.0, 60.0, 85.0, 89.9])
def test_c13_matches_an_independent_quadrature_about_the_mean(kappa, angle):
    assert float(c13_from_angle(angle, kappa)) == pytest.approx(_c13_oracle(angle, kappa), rel=1e-8)


@pytest.mark.parametrize("kappa", [0.5, 5.0, 50.0, 500.0])
@pytest.mark.parametrize("angle", [10.0, 45.0, 80.0])
def test_c23_matches_an_independent_tensor_quadrature(kappa, angle):
    assert float(c23_from_angle(angle, kappa)) == pytest.approx(_c23_oracle(angle, kappa), rel=1e-6)


def test_constants_match_monte_carlo_averages_over_sampled_poles():
    # Statistical oracle: mean |n.t| and mean sin ψ over 40 000 Fisher poles, tolerance 4 sd/sqrt(n).
    n, kappa = 40000, 8.0
    mean = pole_from_dip(50.0, 210.0)
    poles = sample_fisher(np.random.default_rng(2024), mean, kappa, n)  # fixed seed
    for direction in (vector_from_trend_plunge(0.0, 0.0), vector_from_trend_plunge(210.0, 40.0), [0, 0, 1.0]):
        cosine = np.abs(poles @ direction)
        assert abs(cosine.mean() - 1.0 / float(c13(direction, mean, kappa))) < 4 * cosine.std() / math.sqrt(n)
        sine = np.sqrt(1.0 - np.clip(poles @ direction, -1, 1) ** 2)
        assert abs(sine.mean() - 1.0 / float(c23(direction, mean, kappa))) < 4 * sine.std() / math.sqrt(n)


def test_constants_are_axial_in_the_angle():
    for function in (c13_from_angle, c23_from_angle):
        values = function([35.0, 145.0, -35.0, 395.0, 215.0], 12.0)
        np.testing.assert_allclose(values, values[0], rtol=1e-13)


def test_c13_grows_and_c23_shrinks_as_the_line_turns_away_from_the_mean():
    angles = np.linspace(0.0, 90.0, 91)
    for kappa in (0.5, 10.0, 1e4):
        assert (np.diff(c13_from_angle(angles, kappa)) > 0).all()
        assert (np.diff(c23_from_angle(angles, kappa)) < 0).all()
        assert (c13_from_angle(angles, kappa) >= 1.0).all() and (c23_from_angle(angles, kappa) >= 1.0).all()


def test_vectorised_call_equals_one_call_per_angle():
    angles = np.array([0.0, 17.0, 44.0, 89.0])
    kappas = np.array([0.0, 3.0, 40.0, 1e6])
    together = c13_from_angle(angles[:, None], kappas)
    assert together.shape == (4, 4)
    for i, angle in enumerate(angles):
        for j, kappa in enumerate(kappas):
            assert together[i, j] == pytest.approx(float(c13_from_angle(angle, kappa)), rel=1e-14)


def test_vector_form_uses_the_angle_to_the_mean_pole_of_either_sign():
    mean = pole_from_dip(60.0, 45.0)
    lines = vector_from_trend_plunge([0.0, 90.0, 200.0], [10.0, 45.0, 80.0])
    angles = angle_between(lines, mean)
    np.testing.assert_allclose(c13(lines, mean, 15.0), c13_from_angle(angles, 15.0), rtol=1e-13)
    np.testing.assert_allclose(c23(lines, -mean, 15.0), c23_from_angle(angles, 15.0), rtol=1e-13)


def test_intensity_conversions_by_hand_and_round_trip():
    assert float(p10_from_p32(2.0, 2.0)) == 1.0
    assert float(p21_from_p32(1.0, 4.0 / math.pi)) == pytest.approx(math.pi / 4)
    p32 = np.array([0.0, 0.5, 3.0])
    np.testing.assert_allclose(p32_from_p10(p10_from_p32(p32, 1.7), 1.7), p32, rtol=1e-15)
    np.testing.assert_allclose(p32_from_p21(p21_from_p32(p32, 1.2), 1.2), p32, rtol=1e-15)


def test_terzaghi_weights_by_hand_with_the_cap():
    line = [0.0, 0.0, 1.0]
    poles = vector_from_trend_plunge(0.0, [90.0, 30.0, 0.0, 10.0])  # 0°, 60°, 90°, 80° from the line
    weights = terzaghi_weights(poles, line)
    cap = 1.0 / math.sin(math.radians(15.0))
    np.testing.assert_allclose(weights, [1.0, 2.0, cap, cap], rtol=1e-12)
    np.testing.assert_allclose(terzaghi_weights(poles, line, min_angle_deg=5.0)[3], 1 / math.cos(math.radians(80)))


def _three_sets():
    """Three Fisher sets in the spirit of Kiran & Juneja 2022: two steep, one flat (poles, κ, P32 m²/m³)."""
    poles = pole_from_dip([80.0, 75.0, 10.0], [40.0, 130.0, 200.0])
    return poles, np.array([25.0, 15.0, 40.0]), np.array([1.0, 2.0, 0.5])


def _exact_observations(poles, kappas, p32, lines, faces):
    p10 = sum(p32[s] / c13(lines, poles[s], kappas[s]) for s in range(len(p32)))
    p21 = sum(p32[s] / c23(faces, poles[s], kappas[s]) for s in range(len(p32)))
    return p10, p21


LINES = vector_from_trend_plunge([0.0, 90.0, 45.0, 135.0, 0.0], [0.0, 0.0, 30.0, 10.0, 90.0])
FACES = pole_from_dip([90.0, 60.0], [0.0, 270.0])


def test_nnls_recovers_known_p32_per_set_from_exact_data():
    poles, kappas, truth = _three_sets()
    p10, p21 = _exact_observations(poles, kappas, truth, LINES, FACES)
    fit = solve_p32(poles, kappas, line_directions=LINES, p10=p10, p10_counts=np.full(5, 500),
                    face_normals=FACES, p21=p21, p21_counts=[300, 300])
    np.testing.assert_allclose(fit.p32, truth, rtol=1e-9)
    assert (fit.p32 >= 0).all() and not fit.at_bound.any()
    assert fit.chi2 == pytest.approx(0.0, abs=1e-12) and fit.dof == 4
    np.testing.assert_allclose(fit.predicted, fit.observed, rtol=1e-9)
    assert (fit.sd > 0).all() and np.isfinite(fit.sd).all()


def test_nnls_keeps_p32_non_negative_when_the_data_pull_a_set_below_zero():
    poles, kappas, truth = _three_sets()
    truth = np.array([1.0, 0.0, 0.5])
    p10, p21 = _exact_observations(poles, kappas, truth, LINES, FACES)
    p10 = p10 * np.array([0.9, 0.8, 1.0, 1.0, 1.1])  # noise that an unconstrained fit turns into P32_2 < 0
    fit = solve_p32(poles, kappas, line_directions=LINES, p10=p10, face_normals=FACES, p21=p21)
    unconstrained = np.linalg.lstsq(fit.design, fit.observed, rcond=None)[0]
    assert unconstrained[1] < 0
    assert (fit.p32 >= 0).all() and fit.at_bound[1] and fit.p32[1] == 0.0
    assert np.isnan(fit.sd).all() and math.isnan(fit.chi2)  # no counts: no uncertainty claimed


def test_single_isotropic_set_on_one_line_propagates_the_poisson_sd_exactly():
    fit = solve_p32([[0.0, 0.0, 1.0]], [0.0], line_directions=[[1.0, 0.0, 0.0]], p10=[3.0], p10_counts=[144])
    assert fit.p32[0] == pytest.approx(6.0, rel=1e-14)            # P32 = C13 P10 = 2 * 3
    assert fit.sd[0] == pytest.approx(2.0 * 3.0 / 12.0, rel=1e-12)  # C13 * P10 / sqrt(N)


@pytest.mark.slow
def test_stated_uncertainty_matches_the_scatter_of_poisson_surveys():
    # Simulate Poisson counts on scanlines of known length; the spread of the fitted P32 over 300
    # surveys should match the stated sd (within the sampling error of an sd from 300 values, ~4 %).
    poles, kappas, truth = _three_sets()
    p10_true, _ = _exact_observations(poles, kappas, truth, LINES, FACES)
    lengths = 400.0 / p10_true  # about 400 hits per line
    rng = np.random.default_rng(31337)  # fixed seed
    fits = []
    for _ in range(300):
        counts = rng.poisson(p10_true * lengths)
        fits.append(solve_p32(poles, kappas, line_directions=LINES, p10=counts / lengths, p10_counts=counts))
    estimates = np.array([f.p32 for f in fits])
    stated = np.mean([f.sd for f in fits], axis=0)
    np.testing.assert_allclose(estimates.std(axis=0), stated, rtol=0.2)
    assert (np.abs(estimates.mean(axis=0) - truth) < 4 * stated / math.sqrt(300)).all()


def test_solve_refuses_directions_that_cannot_separate_the_sets():
    poles, kappas, truth = _three_sets()
    same = np.tile([1.0, 0.0, 0.0], (4, 1))
    with pytest.raises(ValueError, match="cannot separate"):
        solve_p32(poles, kappas, line_directions=same, p10=[1.0] * 4)


def test_solve_needs_as_many_observations_as_sets():
    poles, kappas, _ = _three_sets()
    with pytest.raises(ValueError, match="at least 3"):
        solve_p32(poles, kappas, line_directions=LINES[:2], p10=[1.0, 1.0])


def test_inputs_are_not_modified():
    poles, kappas, truth = _three_sets()
    p10, p21 = _exact_observations(poles, kappas, truth, LINES, FACES)
    arrays = [poles, kappas, p10, p21, LINES, FACES]
    copies = [a.copy() for a in arrays]
    solve_p32(poles, kappas, line_directions=LINES, p10=p10, face_normals=FACES, p21=p21)
    c13(LINES, poles[0], 3.0)
    terzaghi_weights(poles, LINES[0])
    for original, copy in zip(arrays, copies):
        np.testing.assert_array_equal(original, copy)


@pytest.mark.parametrize(("call", "match"), [
    (lambda: c13_from_angle(30.0, -1.0), "kappa"),
    (lambda: c23_from_angle(np.nan, 1.0), "angle_deg"),
    (lambda: c13([1.0, 0.0, 0.0], None, 5.0), "mean_pole is required"),
    (lambda: c23([0.0, 0.0, 0.0]), "face_normals"),
    (lambda: p10_from_p32(-1.0, 2.0), "p32"),
    (lambda: p32_from_p10(1.0, 0.5), "c13_value"),
    (lambda: p32_from_p21(-0.1, 1.5), "p21"),
    (lambda: terzaghi_weights([[0, 0, 1]], [0, 0, 1], min_angle_deg=0.0), "min_angle_deg"),
    (lambda: terzaghi_weights([[0, 0, 1]], [0, 0, 1], min_angle_deg=90.0), "min_angle_deg"),
    (lambda: terzaghi_weights([[0, 0, 1]], [[0, 0, 1], [1, 0, 0]]), "line_direction"),
    (lambda: solve_p32([[0, 0, 1]], [-1.0], line_directions=[[1, 0, 0]], p10=[1.0]), "kappas"),
    (lambda: solve_p32([[0, 0, 1]], [1.0, 2.0], line_directions=[[1, 0, 0]], p10=[1.0]), "kappas"),
    (lambda: solve_p32([[0, 0, 1]], [1.0], line_directions=[[1, 0, 0]], p10=[1.0, 2.0]), "p10"),
    (lambda: solve_p32([[0, 0, 1]], [1.0], line_directions=[[1, 0, 0]], p10=[-1.0]), "p10"),
    (lambda: solve_p32([[0, 0, 1]], [1.0], line_directions=[[1, 0, 0]], p10=[0.0], p10_counts=[0]),
     "p10_counts"),
    (lambda: solve_p32([[0, 0, 1]], [1.0], line_directions=[[1, 0, 0]], p10=[1.0], p10_counts=[4],
                       p10_sd=[0.5]), "not both"),
    (lambda: solve_p32([[0, 0, 1]], [1.0], line_directions=[[1, 0, 0]], p10=[1.0], p10_counts=[4],
                       face_normals=[[0, 0, 1]], p21=[1.0]), "both the p10 and the p21"),
    (lambda: solve_p32([[0, 0, 1]], [1.0], p10=[1.0]), "line_directions and p10"),
    (lambda: solve_p32(np.empty((0, 3)), [], line_directions=[[1, 0, 0]], p10=[1.0]), "mean_poles"),
])
def test_bad_input_names_the_field(call, match):
    with pytest.raises(ValueError, match=match):
        call()
