r"""Joint sets from poles: a mixture of axial (bipolar) Fisher laws fitted by EM; k by BIC.

A pole and its opposite are the same plane (REFERENCE.md §3), so each set is modelled by the
symmetric ("bipolar") Fisher density on the sphere

.. math:: f(x; \mu, \kappa) = \tfrac12 [F(x; \mu, \kappa) + F(-x; \mu, \kappa)]
          = \frac{\kappa}{4\pi \sinh \kappa} \cosh(\kappa\, \mu \cdot x),

which is the same for x and -x, so a sub-vertical set whose poles fall on both sides of the
stereonet is one set. This module is the 3D counterpart of :mod:`rockmass.dfn.sets2d` (von Mises on
doubled angles): k-means++ starts with the axial distance 1 - |cos|, EM, k by BIC over 1..5 or given,
reproducible from a seed. Each set's reported statistics (mean pole from the orientation tensor, κ,
confidence and variability cones) come from :func:`rockmass.dfn.fit_fisher` on its members, so they
are the same numbers as fitting that set alone.

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
from .intensity import _integer_at_least
from .orientation import _as_scalar, _as_vectors, dip_from_normal, to_lower_hemisphere
from .sets2d import _log_normaliser

__all__ = ["JointSets3D", "fit_sets_3d"]

#: Largest number of sets tried when ``n_sets`` is not given.
MAX_SETS = 5

_MAX_ITER = 300  # EM steps at most
_SHORT_ITER = 30  # EM steps of each initialisation before the best is run on
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
    Free parameters per set: 2 (direction) + 1 (κ) + 1 (weight), less one weight: 4k - 1.

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
    max_sets = _integer_at_least(max_sets, "max_sets", 1, "largest number of sets tried")
    n_init = _integer_at_least(n_init, "n_init", 1, "initialisations per number of sets")
    seed = _integer_at_least(seed, "seed", 0, "root seed of the initialisations")
    n = unit.shape[0]
    n_distinct = np.unique(np.round(unit, 9), axis=0).shape[0]
    if n_sets is not None:
        k_given = _integer_at_least(n_sets, "n_sets", 1, "number of joint sets")
        if k_given > n_distinct:
            raise ValueError(f"n_sets={k_given} but only {n_distinct} distinct pole(s) were given; give fewer "
                             "sets or leave n_sets=None to choose by BIC")
        candidates = [k_given]
    else:
        candidates = list(range(1, min(max_sets, n_distinct) + 1))
    fits = {k: _best_fit(unit, k, kappa_max, seed, n_init) for k in candidates}
    bic = {k: (None if f is None else -2.0 * f[3] + (4 * k - 1) * math.log(n)) for k, f in fits.items()}
    feasible = [k for k in candidates if bic[k] is not None]
    if not feasible:
        raise ValueError(f"could not fit n_sets={candidates[0]} sets: a set emptied during EM; give fewer sets")
    k = min(feasible, key=lambda kk: (bic[kk], kk))
    mu, kappa, pi, loglik, converged, _ = fits[k]
    return _result(unit, mu, kappa, pi, loglik, converged, bic, "given" if n_sets is not None else "bic",
                   resolution)


# -- EM -----------------------------------------------------------------------------------------


def _a3(kappa: np.ndarray) -> np.ndarray:
    """Mean resultant length of a 3D Fisher law, coth κ - 1/κ (κ/3 for small κ)."""
    small = kappa < 1e-4
    safe = np.where(small, 1.0, kappa)
    value = (1.0 + np.exp(-2.0 * safe)) / -np.expm1(-2.0 * safe) - 1.0 / safe
    return np.where(small, kappa / 3.0, value)


def _a3_inverse(rbar: np.ndarray, kappa_max: float) -> np.ndarray:
    """κ with A3(κ) = R̄ in [0, kappa_max]: Banerjee's start, then Newton (A3' = 1/κ² - 1/sinh²κ)."""
    r = np.clip(np.asarray(rbar, dtype=np.float64), 0.0, 1.0)
    capped = r >= _a3(np.float64(kappa_max))
    r_open = np.where(capped, 0.5, r)
    kappa = r_open * (3.0 - r_open**2) / (1.0 - r_open**2)
    for _ in range(30):
        small = kappa < 1e-4
        safe = np.where(small, 1.0, kappa)
        slope = np.where(small, 1.0 / 3.0, 1.0 / safe**2 - 4.0 * np.exp(-2.0 * safe) / np.expm1(-2.0 * safe) ** 2)
        step = (_a3(kappa) - r_open) / np.maximum(slope, 1e-300)
        kappa = np.clip(kappa - step, 0.0, kappa_max)
        if np.all(np.abs(step) <= 1e-12 * np.maximum(kappa, 1.0)):
            break
    return np.where(capped, kappa_max, kappa)


def _log_densities(x: np.ndarray, mu: np.ndarray, kappa: np.ndarray, pi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, k) log π_k + log f(x_i; μ_k, κ_k) (bipolar Fisher, per steradian) and c = x·μ."""
    c = x @ mu.T
    a = np.abs(c)
    log_f = (np.log(_normaliser(kappa)) - _LOG_2PI - kappa * (1.0 - a)
             + np.log1p(np.exp(-2.0 * kappa * a)) - math.log(2.0))
    return np.log(pi) + log_f, c


def _m_step(x: np.ndarray, post: np.ndarray, mu: np.ndarray | None, kappa: np.ndarray | None,
            kappa_max: float) -> tuple | None:
    n_k = post.sum(axis=0)
    if np.any(n_k <= 1e-9 * x.shape[0]):
        return None
    if mu is None:  # first step from hard labels: the orientation tensor's axis gives the direction
        new_mu = np.empty((post.shape[1], 3))
        for j in range(post.shape[1]):
            tensor = (x * post[:, j:j + 1]).T @ x
            new_mu[j] = np.linalg.eigh(tensor)[1][:, -1]
        sign = np.sign(x @ new_mu.T)
        sign[sign == 0] = 1.0
    else:
        sign = np.tanh(kappa * (x @ mu.T))
        new_mu = None
    resultant = (post * sign).T @ x  # (k, 3)
    length = np.linalg.norm(resultant, axis=1)
    if np.any(length <= 0.0):
        return None
    new_mu = resultant / length[:, None]
    rbar = np.minimum(length / n_k, 1.0)
    return new_mu, _a3_inverse(rbar, kappa_max), n_k / n_k.sum()


def _em(x: np.ndarray, post: np.ndarray, kappa_max: float, max_iter: int) -> tuple | None:
    """EM from initial posteriors: (mu, kappa, pi, loglik, converged, posterior) or None."""
    previous = -np.inf
    converged = False
    mu = kappa = None
    loglik = -np.inf
    for _ in range(max_iter):
        params = _m_step(x, post, mu, kappa, kappa_max)
        if params is None:
            return None
        mu, kappa, pi = params
        log_p, _ = _log_densities(x, mu, kappa, pi)
        log_norm = _log_normaliser(log_p)
        loglik = float(log_norm.sum())
        post = np.exp(log_p - log_norm[:, None])
        if loglik - previous <= _TOL * x.shape[0]:
            converged = True
            break
        previous = loglik
    return mu, kappa, pi, loglik, converged, post


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


def _best_fit(x: np.ndarray, k: int, kappa_max: float, seed: int, n_init: int) -> tuple | None:
    if k == 1:
        return _em(x, np.ones((x.shape[0], 1)), kappa_max, _MAX_ITER)
    best = None
    for restart in range(n_init):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k, restart)))
        labels = _kmeans_pp(x, k, rng)
        if labels is None:
            continue
        fit = _em(x, np.eye(k)[labels], kappa_max, _SHORT_ITER)
        if fit is not None and (best is None or fit[3] > best[3]):
            best = fit
    if best is None or best[4]:
        return best
    post = best[5]
    run_on = _em(x, post, kappa_max, _MAX_ITER)
    return best if run_on is None else run_on


def _result(x, mu, kappa, pi, loglik, converged, bic, selected_by, resolution) -> JointSets3D:
    mu = to_lower_hemisphere(mu)
    order = np.lexsort((dip_from_normal(mu)[0], dip_from_normal(mu)[1]))
    mu, kappa, pi = mu[order], kappa[order], pi[order]
    k = mu.shape[0]
    log_p, _ = _log_densities(x, mu, kappa, pi)
    posterior = np.exp(log_p - _log_normaliser(log_p)[:, None])
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
