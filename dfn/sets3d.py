r"""Joint sets from poles: a mixture of axial (bipolar) Fisher laws fitted by EM; k by BIC.

A pole and its opposite are the same plane (docs/fractures.md §1.1), so each set is modelled by the
symmetric ("bipolar") Fisher density on the sphere

.. math:: f(x; \mu, \kappa) = \tfrac12 [F(x; \mu, \kappa) + F(-x; \mu, \kappa)]
          = \frac{\kappa}{4\pi \sinh \kappa} \cosh(\kappa\, \mu \cdot x),

which is the same for x and -x, so a sub-vertical set whose poles fall on both sides of the
stereonet is one set. This module is the 3D counterpart of :mod:`rockmass.dfn.sets2d` (von Mises on
doubled angles): k-means++ starts with the axial distance 1 - |cos|, EM, k by BIC over 1..5 or given,
reproducible from a seed; the EM machinery the two modules share is :mod:`rockmass.dfn._mixture_em`
(docs/fractures.md §4), and this module supplies only the bipolar Fisher law (eq. (3.9)). Each
set's reported statistics (mean pole from the orientation tensor, κ, confidence and variability
cones) come from :func:`rockmass.dfn.fit_fisher` on its members, so they are the same numbers as
fitting that set alone.

Numerical safety: with c = μ·x, the log density is evaluated as

.. math:: \log f = \log\frac{\kappa}{1 - e^{-2\kappa}} - \log 2\pi - \kappa (1 - |c|)
          + \log\frac{1 + e^{-2\kappa|c|}}{2},

which never forms e^κ and tends to -log 4π as κ → 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .fisher import FisherFit, _normaliser, fit_fisher
from ._mixture_em import Components, candidate_set_counts, check_options, fit_mixture, kappa_from_rbar, posteriors
from .orientation import _as_scalar, _as_vectors, dip_from_normal, to_lower_hemisphere

__all__ = ["JointSets3D", "fit_sets_3d"]

#: Largest number of sets tried when ``n_sets`` is not given.
MAX_SETS = 5

_TOL = 1e-7  # convergence: log-likelihood gain per pole in one step
_LOG_2PI = math.log(2.0 * math.pi)


@dataclass(frozen=True)
class JointSets3D:
    """Joint sets found among poles; sets are ordered by the dip direction of their mean plane.

    Attributes
    ----------
    fits : tuple of FisherFit or None
        :func:`~rockmass.dfn.fit_fisher` of each set's members (mean pole from the orientation
        tensor, κ, α95, variability cones); None for a set with fewer than 2 members.
    mean_pole : (k, 3) ndarray of float64
        Lower-hemisphere mean pole of each set (from ``fits``; the mixture's own mean when a set has
        fewer than 2 members).
    count : (k,) ndarray of int64
        Poles assigned to each set (maximum posterior).
    weight : (k,) ndarray of float64
        Mixing proportion of each set; sums to 1.
    mixture_kappa : (k,) ndarray of float64
        The concentration of each component of the fitted mixture (soft memberships).
    membership : (n,) ndarray of int64
        Set of each pole.
    posterior : (n, k) ndarray of float64
        Posterior probability of each set for each pole.
    log_likelihood : float
        Log-likelihood of the poles (per steradian) at the fit.
    bic : dict of int to float or None
        BIC = -2 log L + (4k - 1) ln n for every k tried (None where k sets could not be fitted).
    selected_by : {"bic", "given"}
        How k was chosen.
    converged : bool
        Whether EM met its tolerance before the iteration limit.
    """

    fits: tuple
    mean_pole: np.ndarray
    count: np.ndarray
    weight: np.ndarray
    mixture_kappa: np.ndarray
    membership: np.ndarray
    posterior: np.ndarray
    log_likelihood: float
    bic: dict
    selected_by: str
    converged: bool

    @property
    def n_sets(self) -> int:
        """Number of sets k."""
        return int(self.count.size)

    @property
    def mean_dip_deg(self) -> np.ndarray:
        """Dip of each set's mean plane, degrees."""
        return dip_from_normal(self.mean_pole)[0]

    @property
    def mean_dip_direction_deg(self) -> np.ndarray:
        """Dip direction of each set's mean plane, degrees in [0, 360)."""
        return dip_from_normal(self.mean_pole)[1]


def fit_sets_3d(
    poles: Any,
    n_sets: int | None = None,
    *,
    max_sets: int = MAX_SETS,
    resolution_deg: float = 1.0,
    seed: int = 0,
    n_init: int = 4,
) -> JointSets3D:
    r"""Cluster poles into joint sets: a mixture of bipolar Fisher laws by EM, k by BIC.

    Parameters
    ----------
    poles : (n, 3) array_like
        Plane normals or poles of either sign (normalised here; not modified), n >= 1.
    n_sets : int, optional
        Number of sets k >= 1. Default None: k in 1..``max_sets`` with the smallest BIC.
    max_sets : int, default 5
        Largest k tried when ``n_sets`` is None (capped at the number of distinct poles).
    resolution_deg : float, default 1.0
        Reading resolution δ of the orientations (0 < δ < 90 degrees); κ of each component is capped
        at 1 / (1 - cos δ) (the bound of :func:`~rockmass.dfn.fit_fisher`), which keeps EM away from
        the unbounded likelihood of a set collapsed onto one reading.
    seed : int, default 0
        Root seed of the initialisations (``SeedSequence(seed, spawn_key=(k, restart))``).
    n_init : int, default 4
        Initialisations per k >= 2; the one with the largest likelihood is kept.

    Returns
    -------
    JointSets3D

    Raises
    ------
    ValueError
        No poles, a zero or non-finite pole, ``n_sets`` larger than the number of distinct poles.

    Notes
    -----
    EM for the bipolar mixture: with a latent sign s per pole, the posterior of s = +1 within set k
    is (1 + tanh(κ_k μ_k·x_i))/2, so the M-step uses the signed resultant
    :math:`r_k = \sum_i p_{ik} \tanh(\kappa_k \mu_k \cdot x_i)\, x_i`:
    :math:`\mu_k = r_k/|r_k|`, :math:`\bar R_k = |r_k| / \sum_i p_{ik}` and
    :math:`\kappa_k = A_3^{-1}(\bar R_k)` with :math:`A_3(\kappa) = \coth\kappa - 1/\kappa`
    (Banerjee et al. 2005 start :math:`\bar R(3 - \bar R^2)/(1 - \bar R^2)`, then Newton steps).
    Free parameters per set: 2 (direction) + 1 (κ) + 1 (weight), less one weight: 4k - 1
    (docs/fractures.md §4, eqs. (4.1)-(4.5)).

    References
    ----------
    .. [1] Banerjee, A., Dhillon, I. S., Ghosh, J., Sra, S. (2005). Clustering on the unit hypersphere
       using von Mises-Fisher distributions. JMLR 6, 1345-1382.
    .. [2] Fisher, N. I., Lewis, T., Embleton, B. J. J. (1987). Statistical Analysis of Spherical
       Data. Cambridge University Press, §3.2.4 and §7 (axial data).
    .. [3] Schwarz, G. (1978). Estimating the dimension of a model. Ann. Stat. 6, 461-464.

    Examples
    --------
    >>> poles = [[0.05, 0, -1], [-0.05, 0, -1], [0, 0.05, -1], [1, 0.05, 0], [-1, 0.05, 0], [1, -0.05, 0.02]]
    >>> sets = fit_sets_3d(poles, n_sets=2)   # six poles are too few for BIC to choose
    >>> sets.n_sets, sets.membership.tolist(), sets.mean_dip_deg.round(0).tolist()
    (2, [1, 1, 1, 0, 0, 0], [90.0, 1.0])
    """
    unit = _as_vectors(poles, "poles")
    if unit.ndim != 2 or unit.shape[0] == 0:
        raise ValueError(f"poles must be an (n, 3) array with n >= 1, got shape {unit.shape}")
    unit = to_lower_hemisphere(unit)
    resolution = _as_scalar(resolution_deg, "resolution_deg", low=0.0, low_open=True, high=90.0,
                            what="reading resolution of an orientation in degrees")
    kappa_max = 1.0 / (2.0 * math.sin(math.radians(resolution) / 2.0) ** 2)
    max_sets, n_init, seed = check_options(max_sets, n_init, seed)
    n = unit.shape[0]
    n_distinct = np.unique(np.round(unit, 9), axis=0).shape[0]
    candidates = candidate_set_counts(n_sets, max_sets, n_distinct, "distinct pole(s) were given")
    fit, bic, _ = fit_mixture(_Poles(unit, kappa_max), n, candidates, seed, n_init, lambda k: 4 * k - 1, n)
    return _result(unit, fit.components, fit.log_likelihood, fit.converged, bic,
                   "given" if n_sets is not None else "bic", resolution)


# -- the bipolar Fisher law on poles -----------------------------------------------------------


def _a3(kappa: np.ndarray) -> np.ndarray:
    """Mean resultant length of a 3D Fisher law, coth κ - 1/κ (κ/3 for small κ)."""
    small = kappa < 1e-4
    safe = np.where(small, 1.0, kappa)
    value = (1.0 + np.exp(-2.0 * safe)) / -np.expm1(-2.0 * safe) - 1.0 / safe
    return np.where(small, kappa / 3.0, value)


def _a3_slope(kappa: np.ndarray, a: np.ndarray) -> np.ndarray:
    """A3'(κ) = 1/κ² - 1/sinh²κ, written with e^(-2κ) (no overflow); 1/3 as κ -> 0."""
    small = kappa < 1e-4
    safe = np.where(small, 1.0, kappa)
    return np.where(small, 1.0 / 3.0, 1.0 / safe**2 - 4.0 * np.exp(-2.0 * safe) / np.expm1(-2.0 * safe) ** 2)


def _a3_inverse(rbar: np.ndarray, kappa_max: float) -> np.ndarray:
    """κ with A3(κ) = R̄ in [0, kappa_max]: Banerjee's start, then Newton steps."""
    return kappa_from_rbar(rbar, kappa_max, 3, _a3, _a3_slope)


def _log_densities(x: np.ndarray, mu: np.ndarray, kappa: np.ndarray, pi: np.ndarray) -> np.ndarray:
    """(n, k) log π_k + log f(x_i; μ_k, κ_k) (bipolar Fisher, per steradian)."""
    a = np.abs(x @ mu.T)
    log_f = (np.log(_normaliser(kappa)) - _LOG_2PI - kappa * (1.0 - a)
             + np.log1p(np.exp(-2.0 * kappa * a)) - math.log(2.0))
    return np.log(pi) + log_f


class _Poles:
    """Unit poles on the lower hemisphere: the bipolar Fisher mixture model that the shared EM fits."""

    def __init__(self, x: np.ndarray, kappa_max: float) -> None:
        self.x = x
        self.kappa_max = kappa_max
        self.weights = np.ones(x.shape[0])
        self.tolerance = _TOL * x.shape[0]

    def log_densities(self, components: Components) -> np.ndarray:
        return _log_densities(self.x, components.mean, components.kappa, components.weight)

    def m_step(self, post: np.ndarray, previous: Components | None) -> Components | None:
        """M-step with the latent sign of each pole (see :func:`fit_sets_3d`, Notes)."""
        x = self.x
        n_k = post.sum(axis=0)
        if np.any(n_k <= 1e-9 * x.shape[0]):
            return None
        if previous is None:  # first step from hard labels: the orientation tensor's axis gives the direction
            axes = np.empty((post.shape[1], 3))
            for j in range(post.shape[1]):
                tensor = (x * post[:, j:j + 1]).T @ x
                axes[j] = np.linalg.eigh(tensor)[1][:, -1]
            sign = np.sign(x @ axes.T)
            sign[sign == 0] = 1.0
        else:
            sign = np.tanh(previous.kappa * (x @ previous.mean.T))
        resultant = (post * sign).T @ x  # (k, 3)
        length = np.linalg.norm(resultant, axis=1)
        if np.any(length <= 0.0):
            return None
        rbar = np.minimum(length / n_k, 1.0)
        return Components(resultant / length[:, None], _a3_inverse(rbar, self.kappa_max), n_k / n_k.sum(), rbar)

    def initial_labels(self, k: int, rng: np.random.Generator) -> np.ndarray | None:
        return _kmeans_pp(self.x, k, rng)


def _kmeans_pp(x: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray | None:
    """Hard labels: k-means++ seeding and axial spherical k-means (distance 1 - |cos|)."""
    centres = [x[rng.integers(x.shape[0])]]
    for _ in range(1, k):
        dist = np.min(1.0 - np.abs(x @ np.array(centres).T), axis=1)
        mass = np.maximum(dist, 0.0)
        if mass.sum() <= 0.0:
            return None
        centres.append(x[rng.choice(x.shape[0], p=mass / mass.sum())])
    centres = np.array(centres)
    labels = None
    for _ in range(10):
        new = np.argmax(np.abs(x @ centres.T), axis=1)
        if np.any(np.bincount(new, minlength=k) == 0):
            return None
        if labels is not None and np.array_equal(new, labels):
            break
        labels = new
        for j in range(k):
            members = x[labels == j]
            centres[j] = np.linalg.eigh(members.T @ members)[1][:, -1]
    return labels


def _result(x, components: Components, loglik, converged, bic, selected_by, resolution) -> JointSets3D:
    mu, kappa, pi = to_lower_hemisphere(components.mean), components.kappa, components.weight
    order = np.lexsort((dip_from_normal(mu)[0], dip_from_normal(mu)[1]))
    mu, kappa, pi = mu[order], kappa[order], pi[order]
    k = mu.shape[0]
    posterior = posteriors(_log_densities(x, mu, kappa, pi))
    membership = np.argmax(posterior, axis=1).astype(np.int64)
    count = np.bincount(membership, minlength=k).astype(np.int64)
    fits: list[FisherFit | None] = []
    means = np.empty((k, 3))
    for j in range(k):
        members = x[membership == j]
        fit = fit_fisher(members, resolution_deg=resolution) if members.shape[0] >= 2 else None
        fits.append(fit)
        means[j] = mu[j] if fit is None else fit.mean_pole
    return JointSets3D(
        fits=tuple(fits),
        mean_pole=means,
        count=count,
        weight=pi,
        mixture_kappa=kappa,
        membership=membership,
        posterior=posterior,
        log_likelihood=loglik,
        bic=bic,
        selected_by=selected_by,
        converged=converged,
    )
