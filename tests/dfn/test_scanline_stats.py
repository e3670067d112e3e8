"""Scanline statistics: RQD closed form, hand-made lines, Terzaghi weights by hand, spacing fits."""

import json
import math

import numpy as np
import pytest

from rockmass.dfn.scanline import Scanline
from rockmass.dfn.scanline_stats import fit_spacings, rqd_direct, rqd_priest_hudson, scanline_statistics


def _line(distances, dips, dip_directions, *, trend=0.0, plunge=90.0, length=2.0):
    return Scanline(distance_m=distances, dip_deg=dips, dip_direction_deg=dip_directions, trend_deg=trend,
                    plunge_deg=plunge, length_m=length)


def test_priest_hudson_rqd_at_ten_joints_per_metre_is_73_6_percent():
    # by hand: 100 e^(-10 * 0.1) (10 * 0.1 + 1) = 200 / e = 73.5759
    assert float(rqd_priest_hudson(10.0)) == pytest.approx(200.0 / math.e, rel=1e-14)
    assert round(float(rqd_priest_hudson(10.0)), 1) == 73.6
    assert float(rqd_priest_hudson(0.0)) == 100.0


def test_hand_made_scanline_has_exact_p10_and_direct_rqd():
    # a vertical 2 m line through 5 horizontal joints: pieces 0.3, 0.05, 0.65, 0.05, 0.45, 0.5;
    # those >= 0.1 m add to 1.9 m, so RQD = 95 %; P10 = 5 / 2
    line = _line([0.3, 0.35, 1.0, 1.05, 1.5], [0] * 5, [0] * 5)
    stats = scanline_statistics(line)
    total = stats["all"]
    assert total["n_intersections"] == 5
    assert total["p10_per_m"] == 2.5
    assert total["p10_terzaghi_per_m"] == pytest.approx(2.5, rel=1e-15)  # planes normal to the line
    assert total["rqd_direct_percent"] == pytest.approx(95.0, rel=1e-12)
    assert total["rqd_priest_hudson_percent"] == pytest.approx(100 * math.exp(-0.25) * 1.25, rel=1e-14)
    assert total["spacing_m"]["mean_m"] == pytest.approx(0.3, rel=1e-12)


def test_direct_rqd_counts_a_piece_of_exactly_the_threshold():
    assert rqd_direct([0.1, 0.2], length_m=0.3) == pytest.approx(100.0)
    assert rqd_direct([], length_m=0.05) == 0.0
    assert rqd_direct([], length_m=3.0) == 100.0


def test_terzaghi_p10_matches_one_over_cos_by_hand_with_the_cap():
    # horizontal line due East; planes dipping East at 90, 60 and 10 degrees:
    # |cos delta| = sin(dip) = 1, 0.8660, 0.1736; the last is inside a 15° blind zone -> 1/sin 15°
    line = _line([1.0, 2.0, 3.0], [90.0, 60.0, 10.0], [90.0, 90.0, 90.0], trend=90.0, plunge=0.0, length=4.0)
    by_hand = [1.0, 1.0 / math.sin(math.radians(60.0)), 1.0 / math.sin(math.radians(15.0))]
    stats = scanline_statistics(line, terzaghi_cap_deg=15.0)
    assert stats["all"]["p10_terzaghi_per_m"] == pytest.approx(sum(by_hand) / 4.0, rel=1e-12)
    assert stats["all"]["n_terzaghi_capped"] == 1
    by_hand[2] = 1.0 / math.sin(math.radians(10.0))  # a 5° cap no longer bites
    stats = scanline_statistics(line, terzaghi_cap_deg=5.0)
    assert stats["all"]["p10_terzaghi_per_m"] == pytest.approx(sum(by_hand) / 4.0, rel=1e-12)
    assert stats["all"]["n_terzaghi_capped"] == 0


def test_sets_get_their_own_spacings_and_p10():
    line = _line([0.2, 0.5, 0.9, 1.4, 1.8], [0, 90, 0, 90, 0], [0, 90, 0, 90, 0], length=2.0)
    stats = scanline_statistics(line, membership=[0, 1, 0, 1, 0])
    first, second = stats["sets"]
    assert first["p10_per_m"] == 1.5 and second["p10_per_m"] == 1.0
    assert first["spacing_m"]["mean_m"] == pytest.approx(0.8)  # 0.7 and 0.9
    assert second["spacing_m"]["n"] == 1 and second["spacing_m"]["exponential"]["rate_per_m"] is None
    assert second["p10_terzaghi_per_m"] == pytest.approx(2 / math.sin(math.radians(15.0)) / 2.0)


def test_exponential_mle_rate_is_one_over_the_mean():
    spacings = [0.1, 0.4, 0.25, 1.3, 0.05]
    fit = fit_spacings(spacings)
    assert fit.exponential_rate_per_m == pytest.approx(1.0 / np.mean(spacings), rel=1e-15)
    logs = np.log(spacings)
    assert fit.lognormal_mu == pytest.approx(logs.mean()) and fit.lognormal_sigma == pytest.approx(logs.std())


def test_poisson_line_has_exponential_spacings_and_priest_hudson_rqd():
    rng = np.random.default_rng(11)  # fixed seed
    lam, length = 10.0, 400.0
    positions = np.sort(rng.uniform(0.0, length, rng.poisson(lam * length)))
    fit = fit_spacings(np.diff(positions))
    assert fit.exponential_ks_p > 0.01
    assert fit.exponential_rate_per_m == pytest.approx(lam, rel=3 / math.sqrt(lam * length))
    # direct RQD of a Poisson line converges to the closed form (sd ~ 0.5 % here)
    assert rqd_direct(positions, length) == pytest.approx(float(rqd_priest_hudson(lam)), abs=2.0)


def test_lognormal_spacings_prefer_the_lognormal_law():
    rng = np.random.default_rng(5)  # fixed seed
    fit = fit_spacings(rng.lognormal(-1.0, 0.4, 400))
    assert fit.preferred == "lognormal" and fit.lognormal_sigma == pytest.approx(0.4, rel=0.15)


def test_undefined_values_are_none_and_the_summary_is_strict_json():
    line = _line([1.0], [30.0], [45.0])
    stats = scanline_statistics(line)
    json.dumps(stats, allow_nan=False)
    assert stats["all"]["spacing_m"]["mean_m"] is None
    assert stats["sets"][0]["kappa"] is None  # no Fisher fit given


def test_zero_spacings_are_left_out_of_the_lognormal():
    fit = fit_spacings([0.0, 0.5, 1.0, 0.2])
    assert fit.n_zero == 1 and fit.lognormal_mu is not None and fit.lognormal_aic is None


def test_a_line_parallel_to_a_set_warns():
    from rockmass.dfn import fit_fisher, pole_from_dip

    line = _line([0.5, 1.0], [85.0, 86.0], [0.0, 2.0], trend=90.0, plunge=0.0)  # planes strike East
    fit = fit_fisher(pole_from_dip([85.0, 86.0], [0.0, 2.0]))
    stats = scanline_statistics(line, membership=[0, 0], set_fits=[fit])
    assert stats["warnings"] and "set 0" in stats["warnings"][0]


@pytest.mark.parametrize("kwargs, match", [
    ({"terzaghi_cap_deg": 0.0}, "terzaghi_cap_deg"),
    ({"terzaghi_cap_deg": 90.0}, "terzaghi_cap_deg"),
    ({"rqd_threshold_m": -0.1}, "rqd_threshold_m"),
    ({"membership": [0]}, "membership"),
])
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        scanline_statistics(_line([1.0, 1.5], [0, 0], [0, 0]), **kwargs)


@pytest.mark.slow
def test_terzaghi_p10_of_a_long_synthetic_line_estimates_p32_per_set():
    """Thinning oracle: Poisson(P32 L) Fisher fractures, each hit with probability |n.t| (REFERENCE §4).

    Raw P10 must be P32 / C13 (stereology) and the Terzaghi-weighted P10 must be P32, each within 3
    standard deviations of its Poisson spread; the sets found by BIC must be the three drawn.
    """
    from rockmass.dfn import (angle_between, c13, dip_from_normal, pole_from_dip, sample_fisher,
                              terzaghi_weights, vector_from_trend_plunge)
    from rockmass.dfn.sets3d import fit_sets_3d

    rng = np.random.default_rng(2024)  # fixed seed
    truth = ((50.0, 270.0), (80.0, 10.0), (70.0, 150.0))  # Kiran & Juneja 2022, Table 1
    p32, kappa, length = 1.5, 30.0, 300.0
    line = vector_from_trend_plunge(135.0, 10.0)
    poles, labels = [], []
    for j, (dip, dip_direction) in enumerate(truth):
        candidates = sample_fisher(rng, pole_from_dip(dip, dip_direction), kappa, rng.poisson(p32 * length))
        kept = candidates[rng.random(candidates.shape[0]) < np.abs(candidates @ line)]
        poles.append(kept)
        labels.append(np.full(kept.shape[0], j))
    poles, labels = np.vstack(poles), np.concatenate(labels)
    distance = rng.uniform(0.0, length, labels.size)
    order = np.argsort(distance)
    dip, dip_direction = dip_from_normal(poles[order])
    scanline = Scanline(distance_m=distance[order], dip_deg=dip, dip_direction_deg=dip_direction,
                        trend_deg=135.0, plunge_deg=10.0, length_m=length)
    sets = fit_sets_3d(scanline.poles())
    assert sets.n_sets == 3
    stats = scanline_statistics(scanline, sets.membership, sets.fits)
    true_poles = pole_from_dip(*np.array(truth).T)
    for j, entry in enumerate(stats["sets"]):
        true = int(np.argmin(angle_between(true_poles, entry["mean_pole_xyz"])))
        expected_p10 = p32 / float(c13(line, true_poles[true], kappa))
        assert entry["p10_per_m"] == pytest.approx(expected_p10, abs=3.0 * math.sqrt(expected_p10 * length) / length)
        # a compound Poisson sum: the sd of sum(w) / L is sqrt(sum(w^2)) / L
        weights = terzaghi_weights(scanline.poles()[sets.membership == j], line)
        assert entry["p10_terzaghi_per_m"] == pytest.approx(p32, abs=3.0 * math.sqrt(np.sum(weights**2)) / length)


def test_normal_spacing_is_the_apparent_spacing_times_cos_delta():
    from rockmass.dfn import fit_fisher, pole_from_dip

    # horizontal line due East, planes dipping 60° East: |cos delta| = sin 60°
    line = _line([0.5, 1.5, 2.5], [60.0, 60.0, 60.0], [90.0, 90.0, 90.0], trend=90.0, plunge=0.0, length=3.0)
    fit = fit_fisher(pole_from_dip([60.0, 60.0, 60.0], [90.0, 90.0, 90.0]))
    entry = scanline_statistics(line, [0, 0, 0], [fit])["sets"][0]
    assert entry["angle_line_to_pole_deg"] == pytest.approx(30.0, abs=1e-9)
    assert entry["mean_normal_spacing_m"] == pytest.approx(math.sin(math.radians(60.0)), rel=1e-9)
