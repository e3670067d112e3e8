"""Expectation-maximisation for mixtures of axial orientation laws: the machinery both set finders share.

:mod:`rockmass.dfn.sets2d` (von Mises laws on doubled trace angles) and
:mod:`rockmass.dfn.sets3d` (bipolar Fisher laws on poles) differ only in their component law. Each
describes its data and law by a small model object (see :class:`_MixtureModel`); this module owns
what is the same for both (docs/fractures.md §4):

- the EM loop with its convergence rule (:func:`run_em`),
- k-means++ starts, a short EM run from each and the best run on to convergence (:func:`best_fit`),
- the choice of the number of sets k by BIC (:func:`fit_mixture`; Schwarz 1978),
- the Newton inversion κ = A⁻¹(R̄) of a mean resultant length (:func:`kappa_from_rbar`; Banerjee et al.
  2005),
- the row-wise log-sum-exp (:func:`log_normaliser`).

The result of one EM run is a :class:`MixtureFit`, not a tuple read by position.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .intensity import _integer_at_least

_MAX_ITER = 300  # EM steps at most (over-fitted sets crawl; their BIC only needs a few digits)
_SHORT_ITER = 30  # EM steps of each initialisation before the best is run on


@dataclass(frozen=True)
class Components:
    """The parameters of k mixture components after an M-step.

    Attributes
    ----------
    mean : (k,) or (k, 3) ndarray of float64
        Mean direction of each component: a doubled angle in radians (2D) or a unit vector (3D).
    kappa : (k,) ndarray of float64
        Concentration of each component, in [0, kappa_max].
    weight : (k,) ndarray of float64
        Mixing proportions π_k; they sum to 1.
    rbar : (k,) ndarray of float64
        Weighted mean resultant length R̄_k in [0, 1] from which κ_k was solved.
    """

    mean: np.ndarray
    kappa: np.ndarray
    weight: np.ndarray
    rbar: np.ndarray


@dataclass(frozen=True)
class MixtureFit:
    """One EM run: its final components, log-likelihood, convergence flag and posteriors.

    Attributes
    ----------
    components : Components
        Parameters of the last M-step.
    log_likelihood : float
        Weighted log-likelihood of the data under ``components`` (in the model's own measure).
    converged : bool
        Whether the log-likelihood gain of one step fell below the model's tolerance before the
        iteration limit.
    posterior : (n, k) ndarray of float64
        Posterior probability of each component for each datum, from ``components``.
    """

    components: Components
    log_likelihood: float
    converged: bool
    posterior: np.ndarray


class _MixtureModel(Protocol):
    """What a component law supplies to the shared EM (sets2d's and sets3d's model classes)."""

    #: Weight of each datum, (n,); the log-likelihood is ``weights · log p(x_i)``.
    weights: np.ndarray
    #: Convergence: a log-likelihood gain per step at most this ends EM.
    tolerance: float

    def m_step(self, post: np.ndarray, previous: Components | None) -> Components | None:
        """Components from posteriors (None when a component empties)."""

    def log_densities(self, components: Components) -> np.ndarray:
        """(n, k) log π_k + log f(x_i; component k)."""

    def initial_labels(self, k: int, rng: np.random.Generator) -> np.ndarray | None:
        """Hard labels of a k-means++ start, or None when k distinct centres cannot be drawn."""


def log_normaliser(log_p: np.ndarray) -> np.ndarray:
    """Row-wise log-sum-exp, shifted by the row maximum."""
    top = log_p.max(axis=1)
    return top + np.log(np.exp(log_p - top[:, None]).sum(axis=1))


def posteriors(log_p: np.ndarray) -> np.ndarray:
    """Rows of ``exp(log_p)`` normalised to sum to 1, without overflow."""
    return np.exp(log_p - log_normaliser(log_p)[:, None])


def run_em(model: _MixtureModel, post: np.ndarray, max_iter: int) -> MixtureFit | None:
    """EM from initial posteriors ``post`` (n, k); None when a component empties.

    Each step is an M-step from the posteriors followed by an E-step; EM stops once the weighted
    log-likelihood rises by at most ``model.tolerance`` in one step (converged) or after ``max_iter``
    steps.
    """
    previous = -np.inf
    converged = False
    components = None
    loglik = -np.inf
    for _ in range(max_iter):
        components = model.m_step(post, components)
        if components is None:
            return None
        log_p = model.log_densities(components)
        log_norm = log_normaliser(log_p)
        loglik = float((model.weights * log_norm).sum())
        post = np.exp(log_p - log_norm[:, None])
        if loglik - previous <= model.tolerance:
            converged = True
            break
        previous = loglik
    return MixtureFit(components, loglik, converged, post)


def best_fit(model: _MixtureModel, n: int, k: int, seed: int, n_init: int) -> MixtureFit | None:
    """The best of ``n_init`` short EM runs from k-means++ starts, run on to convergence.

    k = 1 needs no start: EM runs from all data in the one component. Restart r of k draws from
    ``SeedSequence(seed, spawn_key=(k, restart))``, so a fit is reproducible and independent of the
    other k tried. If running the best start on empties a component, the short run is kept (its
    ``converged`` is False).
    """
    if k == 1:
        return run_em(model, np.ones((n, 1)), _MAX_ITER)
    best = None
    for restart in range(n_init):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k, restart)))
        labels = model.initial_labels(k, rng)
        if labels is None:
            continue
        fit = run_em(model, np.eye(k)[labels], _SHORT_ITER)
        if fit is not None and (best is None or fit.log_likelihood > best.log_likelihood):
            best = fit
    if best is None or best.converged:
        return best
    run_on = run_em(model, best.posterior, _MAX_ITER)
    return best if run_on is None else run_on


def check_options(max_sets, n_init, seed) -> tuple[int, int, int]:
    """Validate the options both set finders take (each message names its argument)."""
    return (_integer_at_least(max_sets, "max_sets", 1, "largest number of sets tried"),
            _integer_at_least(n_init, "n_init", 1, "initialisations per number of sets"),
            _integer_at_least(seed, "seed", 0, "root seed of the initialisations"))


def candidate_set_counts(n_sets, max_sets: int, n_distinct: int, distinct_what: str) -> list[int]:
    """The numbers of sets k to try: ``[n_sets]`` when given, else 1..min(max_sets, n_distinct).

    ``distinct_what`` completes the error raised when more sets are asked for than there are
    distinct data, e.g. ``"distinct pole(s) were given"``.
    """
    if n_sets is None:
        return list(range(1, min(max_sets, n_distinct) + 1))
    k_given = _integer_at_least(n_sets, "n_sets", 1, "number of joint sets")
    if k_given > n_distinct:
        raise ValueError(f"n_sets={k_given} but only {n_distinct} {distinct_what}; give fewer sets or leave "
                         "n_sets=None to choose by BIC")
    return [k_given]


#: When k is chosen (not given), a fit with a set of fewer effective members than this is not a
#: candidate: one joint is not a set (a set is a group of near-parallel joints), and a component on
#: one datum always gains likelihood (κ up to its cap), which BIC's penalty on a few data does not
#: outweigh (three near-parallel traces split into two sets 5 degrees apart).
MIN_SET_MEMBERS = 2.0


def set_members(weights: np.ndarray, posterior: np.ndarray) -> np.ndarray:
    """Effective number of members of each set: Kish's (Σ_i r_ik)² / Σ_i r_ik² of the data's
    weights shared out by the posteriors, r_ik = w_i p_ik (two equal members: 2; one: 1, whatever
    its weight).

    Examples
    --------
    >>> set_members(np.array([1.0, 1.0, 5.0]), np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]))
    array([2., 1.])
    """
    r = np.asarray(weights, dtype=np.float64)[:, None] * np.asarray(posterior, dtype=np.float64)
    return r.sum(axis=0) ** 2 / np.maximum((r * r).sum(axis=0), 1e-300)


def fit_mixture(model: _MixtureModel, n: int, candidates: list[int], seed: int, n_init: int,
                free_parameters: Callable[[int], int], n_bic: float) -> tuple[MixtureFit, dict, int]:
    """Fit every k in ``candidates`` and keep the one of smallest BIC (the smaller k on a tie).

    BIC = -2 log L + p(k) ln ``n_bic`` with p = ``free_parameters(k)`` (Schwarz 1978). With more than
    one candidate, a k > 1 with a set of fewer than :data:`MIN_SET_MEMBERS` effective members
    (:func:`set_members`) is left out of the choice (its BIC is still reported).

    Returns
    -------
    fit : MixtureFit
        The chosen fit.
    bic : dict of int to float or None
        BIC of every k tried, None where k components could not be fitted.
    k : int
        The chosen number of sets.
    """
    fits = {k: best_fit(model, n, k, seed, n_init) for k in candidates}
    bic = {k: (None if f is None else -2.0 * f.log_likelihood + free_parameters(k) * math.log(n_bic))
           for k, f in fits.items()}
    feasible = [k for k in candidates if bic[k] is not None]
    if len(candidates) > 1:
        populated = [k for k in feasible if k == 1 or set_members(
            model.weights, fits[k].posterior).min() >= MIN_SET_MEMBERS - 1e-9]
        feasible = populated or feasible[:1]
    if not feasible:
        raise ValueError(f"could not fit n_sets={candidates[0]} sets: a set emptied during EM; give fewer sets")
    k = min(feasible, key=lambda kk: (bic[kk], kk))
    return fits[k], bic, k


def kappa_from_rbar(rbar: np.ndarray, kappa_max: float, dimension: int,
                    mean_length: Callable[[np.ndarray], np.ndarray],
                    slope: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
    """κ in [0, ``kappa_max``] with A_p(κ) = R̄: Banerjee's start, then Newton steps.

    Parameters
    ----------
    rbar : (k,) ndarray of float64
        Mean resultant lengths, clipped to [0, 1].
    kappa_max : float
        Cap of κ; R̄ >= A_p(kappa_max) gives ``kappa_max`` directly (no 1 - R̄² → 0 division).
    dimension : int
        p = 2 (von Mises) or 3 (Fisher); the start is R̄ (p - R̄²) / (1 - R̄²) (Banerjee et al. 2005).
    mean_length : callable
        A_p(κ), overflow-free.
    slope : callable
        ``slope(kappa, a)``: A_p'(κ) given a = A_p(κ), with its finite κ → 0 limit.
    """
    r = np.clip(np.asarray(rbar, dtype=np.float64), 0.0, 1.0)
    capped = r >= mean_length(np.float64(kappa_max))
    r_open = np.where(capped, 0.5, r)
    kappa = r_open * (dimension - r_open**2) / (1.0 - r_open**2)
    for _ in range(30):
        a = mean_length(kappa)
        step = (a - r_open) / np.maximum(slope(kappa, a), 1e-300)
        kappa = np.clip(kappa - step, 0.0, kappa_max)
        if np.all(np.abs(step) <= 1e-12 * np.maximum(kappa, 1.0)):
            break
    return np.where(capped, kappa_max, kappa)
