"""Joint sets from poles: BIC picks the true number, means within their confidence cones, axial data."""

import numpy as np
import pytest

from rockmass.dfn.fisher import fit_fisher, sample_fisher
from rockmass.dfn.orientation import angle_between, pole_from_dip
from rockmass.dfn.sets3d import fit_sets_3d

SEED001_SETS = ((50.0, 270.0), (80.0, 10.0), (70.0, 150.0))  # Kiran & Juneja 2022, Table 1: dip / dip direction


def _three_sets(n=60, kappa=30.0):
    rng = np.random.default_rng(20261121)  # fixed seed: a draw where nothing is borderline
    return np.vstack([sample_fisher(rng, pole_from_dip(d, dd), kappa, n) for d, dd in SEED001_SETS])


def test_bic_picks_three_sets_and_recovers_the_means():
    poles = _three_sets()
    sets = fit_sets_3d(poles)
    assert sets.n_sets == 3 and sets.selected_by == "bic"
    assert min(v for k, v in sets.bic.items() if k != 3) > sets.bic[3]
    truth = np.array([pole_from_dip(d, dd) for d, dd in SEED001_SETS])
    for j, fit in enumerate(sets.fits):
        true = int(np.argmin(angle_between(truth, fit.mean_pole)))
        # the 95 % confidence cone holds the true mean at 95 %; twice it is a safe tolerance
        assert float(angle_between(truth[true], fit.mean_pole)) < 2.0 * fit.alpha95_deg
        assert fit.kappa == pytest.approx(30.0, rel=0.35)
        # the sets' 95 % variability cones (~26° at kappa 30) barely touch: almost every pole drawn
        # from set `true` is in set j
        assert np.mean(sets.membership[true * 60:(true + 1) * 60] == j) >= 0.95
    assert sets.count.sum() == 180 and sets.count.min() >= 57


def test_set_statistics_equal_fit_fisher_on_the_members():
    poles = _three_sets()
    sets = fit_sets_3d(poles)
    for j, fit in enumerate(sets.fits):
        alone = fit_fisher(poles[sets.membership == j])
        np.testing.assert_allclose(fit.mean_pole, alone.mean_pole)
        assert fit.kappa == alone.kappa and fit.alpha95_deg == alone.alpha95_deg
        np.testing.assert_allclose(sets.mean_pole[j], alone.mean_pole)


def test_sub_vertical_set_dipping_both_ways_stays_one_set():
    rng = np.random.default_rng(7)  # fixed seed
    poles = sample_fisher(rng, pole_from_dip(88.0, 90.0), 40.0, 80)
    poles[poles[:, 2] > 0] *= -1.0  # lower hemisphere: the set appears on both sides of the net
    assert (poles[:, 0] > 0).any() and (poles[:, 0] < 0).any()
    sets = fit_sets_3d(poles)
    assert sets.n_sets == 1
    assert float(angle_between(sets.mean_pole[0], pole_from_dip(88.0, 90.0))) < 2.0 * sets.fits[0].alpha95_deg


def test_the_sign_of_a_pole_does_not_matter():
    poles = _three_sets(n=30)
    flipped = poles.copy()
    flipped[::3] *= -1.0
    a, b = fit_sets_3d(poles), fit_sets_3d(flipped)
    assert np.array_equal(a.membership, b.membership)
    np.testing.assert_allclose(a.mean_pole, b.mean_pole, atol=1e-12)


def test_fit_is_deterministic_by_seed_and_input_is_not_modified():
    poles = _three_sets(n=30)
    before = poles.copy()
    a, b = fit_sets_3d(poles, seed=3), fit_sets_3d(poles, seed=3)
    assert np.array_equal(poles, before)
    assert np.array_equal(a.membership, b.membership) and a.bic == b.bic


def test_given_number_of_sets_is_used():
    sets = fit_sets_3d(_three_sets(n=30), n_sets=2)
    assert sets.n_sets == 2 and sets.selected_by == "given" and list(sets.bic) == [2]
    assert sets.weight.sum() == pytest.approx(1.0)


def test_one_pole_gives_one_set_without_fisher_statistics():
    sets = fit_sets_3d([[0.0, 0.0, -1.0]])
    assert sets.n_sets == 1 and sets.fits == (None,) and sets.count.tolist() == [1]


@pytest.mark.parametrize("poles, kwargs, match", [
    (np.zeros((0, 3)), {}, "n >= 1"),
    ([[0.0, 0.0, 0.0]], {}, "non-zero"),
    ([[0.0, 0.0, np.nan]], {}, "finite"),
    ([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]], {"n_sets": 2}, "distinct pole"),
    ([[0.0, 0.0, -1.0]], {"n_sets": 0}, "n_sets"),
])
def test_bad_input_is_named(poles, kwargs, match):
    with pytest.raises(ValueError, match=match):
        fit_sets_3d(poles, **kwargs)
