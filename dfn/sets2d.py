"""Joint sets from trace angles on a face: a length-weighted mixture of von Mises laws on doubled angles.

A trace angle on a face is axial: θ and θ + 180° are the same trace (docs/fractures.md §1.4: 0-180°,
counter-clockwise from +u). Doubling the angle, x = 2θ, maps axial data one-to-one onto the full
circle, where the von Mises law is the natural model of one set (docs/fractures.md §3.2,
eq. (3.8); Mardia & Jupp 2000, §9.3). This module

- gives each trace one angle (:func:`trace_angles_deg`),
- fits a mixture of k von Mises laws on the doubled angles by expectation-maximisation, weighting each
  trace by its length, and picks k by BIC over 1..5 or takes it as given
  (:func:`fit_axial_mixture` on plain arrays, :func:`fit_sets_2d` on a trace map); the EM machinery
  is shared with :mod:`rockmass.dfn.sets3d` (:mod:`rockmass.dfn._mixture_em`, docs/fractures.md §4),
  and this module supplies only the von Mises law on doubled angles,
- reports per set the mean angle, circular spread, concentration κ, weight, trace count and the hard
  membership of every trace (:class:`JointSets2D`).

Numerical safety: densities are evaluated as logs with the exponentially scaled Bessel function,
:math:`\\log I_0(\\kappa) = \\log(\\mathrm{i0e}(\\kappa)) + \\kappa`, and
:math:`\\cos d - 1 = -2\\sin^2(d/2)`, so no κ overflows and parallel traces lose no precision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import i0e, i1e

from ._mixture_em import Components, candidate_set_counts, check_options, fit_mixture, kappa_from_rbar, posteriors
from .intensity import _choice, _real_at_least
from .tracemap import TraceMap, _require_trace_map

__all__ = ["JointSets2D", "fit_axial_mixture", "fit_sets_2d", "trace_angles_deg"]

#: Largest number of sets tried when ``n_sets`` is not given.
MAX_SETS = 5

#: Default angular resolution of trace angles (degrees): the spread below which sets are not told
#: apart. A 100-pixel trace digitised to one pixel has an angle uncertain by about 0.6°.
RESOLUTION_DEG = 0.5

ANGLE_METHODS = ("segments", "chord")

_TOL = 1e-6  # convergence: log-likelihood gain per unit weight in one step
_LOG_2PI = math.log(2.0 * math.pi)


def trace_angles_deg(trace_map: TraceMap, *, method: str = "segments") -> np.ndarray:
    r"""One axial angle per trace, degrees in [0, 180) counter-clockwise from +x (+u on a face).

    Parameters
    ----------
    trace_map : TraceMap
        The traces.
    method : {"segments", "chord"}, default "segments"
        ``"segments"``: the length-weighted mean axial direction of the trace's straight pieces,
        :math:`\theta = \tfrac12 \arg \sum_j \ell_j e^{2 i \phi_j}` (it follows a curved trace's
        overall course and ignores the order in which it was digitised); when the pieces cancel
        exactly (a symmetric zig-zag) the chord is used. ``"chord"``: the direction from the first to
        the last vertex.

    Returns
    -------
    (n_traces,) ndarray of float64
        Angles in [0, 180); NaN for a trace without a direction (zero length, or a closed trace whose
        pieces cancel).

    References
    ----------
    .. [1] Mardia, K. V., Jupp, P. E. (2000). Directional Statistics. Wiley, §9.3 (axial data, doubled
       angles).

    Examples
    --------
    >>> tm = TraceMap.from_polylines([[(0, 0), (1, 1)], [(0, 0), (-1, 0)], [(0, 0), (2, 0), (3, 1)]])
    >>> trace_angles_deg(tm).round(6).tolist()
    [45.0, 0.0, 17.632195]
    >>> trace_angles_deg(tm, method="chord").round(6).tolist()
    [45.0, 0.0, 18.434949]
    """
    _require_trace_map(trace_map)
    _choice(method, ANGLE_METHODS, "method")
    first = trace_map.xy_m[trace_map.offsets[:-1]]
    last = trace_map.xy_m[trace_map.offsets[1:] - 1]
    chord = last - first
    if method == "segments":
        seg = trace_map.segments()
        dx, dy = seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]
        owner = trace_map.segment_trace_index()
        # l e^{2i phi} = (dx + i dy)^2 / l: doubling the angle removes the digitising direction
        piece = np.hypot(dx, dy)
        safe = np.where(piece > 0.0, piece, 1.0)
        c = np.bincount(owner, weights=(dx * dx - dy * dy) / safe, minlength=trace_map.n_traces)
        s = np.bincount(owner, weights=2.0 * dx * dy / safe, minlength=trace_map.n_traces)
        total = np.bincount(owner, weights=piece, minlength=trace_map.n_traces)
        cancels = np.hypot(c, s) <= 1e-12 * total
        doubled = np.where(cancels, 2.0 * np.arctan2(chord[:, 1], chord[:, 0]), np.arctan2(s, c))
    else:
        cancels = np.ones(trace_map.n_traces, dtype=bool)
        doubled = 2.0 * np.arctan2(chord[:, 1], chord[:, 0])
    undefined = cancels & ~np.any(chord != 0.0, axis=1)
    angles = np.degrees(doubled % (2.0 * np.pi)) / 2.0
    angles[angles >= 180.0] = 0.0  # rounding of values just below 2 pi
    angles[undefined] = np.nan
    return angles


@dataclass(frozen=True)
class JointSets2D:
    """Joint sets found in axial trace angles; sets are ordered by mean angle.

    Attributes
    ----------
    mean_angle_deg : (k,) ndarray of float64
        Mean axial direction of each set, degrees in [0, 180).
    spread_deg : (k,) ndarray of float64
        Circular standard deviation of the axial angle, :math:`\\tfrac12\\sqrt{-2\\ln\\bar R}` in
        degrees, with :math:`\\bar R` the set's length- and posterior-weighted mean resultant length of
        the doubled angles; 0 for parallel traces, inf for a set without a preferred direction.
    kappa : (k,) ndarray of float64
        Von Mises concentration of the doubled angles (maximum likelihood, capped at ``kappa_max``).
    kappa_capped : (k,) ndarray of bool
        Where κ reached ``kappa_max`` (the set is tighter than the angular resolution).
    weight : (k,) ndarray of float64
        Mixing proportion of each set, length-weighted; sums to 1.
    count : (k,) ndarray of int64
        Traces assigned to each set (maximum posterior).
    membership : (n,) ndarray of int64
        Set of each trace, -1 for a trace without a direction.
    posterior : (n, k) ndarray of float64
        Posterior probability of each set for each trace (rows of zeros for traces without a direction).
    angle_deg : (n,) ndarray of float64
        The angles that were clustered (NaN where undefined).
    log_likelihood : float
        Weighted log-likelihood of the axial angles in radians at the fit, weights scaled to sum to the
        effective number of angles n_eff = (sum w)^2 / sum w^2.
    bic : dict of int to float or None
        BIC = -2 log L + (3k - 1) ln n_eff for every k tried (None where k sets could not be fitted:
        fewer distinct angles than k, or a set that emptied during EM).
    selected_by : {"bic", "given"}
        How k was chosen.
    kappa_max : float
        The cap of κ, :math:`1 / (4\\sigma_r^2)` for the angular resolution :math:`\\sigma_r`.
    converged : bool
        Whether EM met its tolerance before the iteration limit.
    """

    mean_angle_deg: np.ndarray
    spread_deg: np.ndarray
    kappa: np.ndarray
    kappa_capped: np.ndarray
    weight: np.ndarray
    count: np.ndarray
    membership: np.ndarray
    posterior: np.ndarray
    angle_deg: np.ndarray
    log_likelihood: float
    bic: dict
    selected_by: str
    kappa_max: float
    converged: bool

    @property
    def n_sets(self) -> int:
        """Number of sets k."""
        return int(self.mean_angle_deg.size)


def fit_sets_2d(
    trace_map: TraceMap,
    n_sets: int | None = None,
    *,
    weights: Any = None,
    method: str = "segments",
    max_sets: int = MAX_SETS,
    resolution_deg: float = RESOLUTION_DEG,
    seed: int = 0,
    n_init: int = 4,
) -> JointSets2D:
    """Joint sets of a trace map: axial clustering of trace angles, length-weighted.

    Parameters
    ----------
    trace_map : TraceMap
        The traces; at least one must have a direction.
    n_sets : int, optional
        Number of sets k >= 1. Default None: chosen by BIC over 1..``max_sets``.
    weights : (n_traces,) array_like of float, optional
        Weight of each trace, >= 0 (e.g. its length clipped to the window). Default None: trace lengths.
    method : {"segments", "chord"}, default "segments"
        Trace angle definition, see :func:`trace_angles_deg`.
    max_sets, resolution_deg, seed, n_init
        As in :func:`fit_axial_mixture`.

    Returns
    -------
    JointSets2D
        ``membership`` has one entry per trace of ``trace_map``.

    Raises
    ------
    ValueError
        An empty map, no trace with a direction and a positive weight, or ``n_sets`` larger than the
        number of distinct angles.

    Examples
    --------
    >>> tm = TraceMap.from_segments([[0, 0, 2, 0.02], [0, 1, 2, 0.98], [0, 0, 0.03, 3], [1, 0, 0.98, 3]])
    >>> sets = fit_sets_2d(tm)
    >>> sets.n_sets, sets.mean_angle_deg.round(1).tolist(), sets.membership.tolist()
    (2, [0.0, 89.9], [0, 0, 1, 1])
    """
    _require_trace_map(trace_map)
    if trace_map.n_traces == 0:
        raise ValueError("trace_map has 0 traces: joint sets need at least one trace")
    angles = trace_angles_deg(trace_map, method=method)
    if weights is None:
        weights = trace_map.lengths_m()
    return fit_axial_mixture(
        angles,
        weights,
        n_sets=n_sets,
        max_sets=max_sets,
        resolution_deg=resolution_deg,
        seed=seed,
        n_init=n_init,
    )


def fit_axial_mixture(
    angles_deg: Any,
    weights: Any = None,
    *,
    n_sets: int | None = None,
    max_sets: int = MAX_SETS,
    resolution_deg: float = RESOLUTION_DEG,
    seed: int = 0,
    n_init: int = 4,
) -> JointSets2D:
    r"""Fit a mixture of von Mises laws to axial angles (θ ≡ θ + 180°) by weighted EM; k by BIC.

    Parameters
    ----------
    angles_deg : (n,) array_like of float
        Axial angles in degrees (any real values; NaN marks an angle to leave out, membership -1).
    weights : (n,) array_like of float, optional
        Weight of each angle, finite and >= 0 (trace lengths for a length-weighted fit). Angles of
        weight 0 do not shape the fit but are still assigned to a set. Default None: all 1.
    n_sets : int, optional
        Number of sets k >= 1. Default None: k in 1..``max_sets`` with the smallest BIC.
    max_sets : int, default 5
        Largest k tried when ``n_sets`` is None (capped at the number of fitted angles).
    resolution_deg : float, default 0.5
        Angular resolution :math:`\sigma_r` of the angles, > 0; κ is capped at
        :math:`1/(4\sigma_r^2)` (radians), the concentration of doubled angles whose axial standard
        deviation is :math:`\sigma_r`.
    seed : int, default 0
        Root seed of the initialisations (``numpy.random.SeedSequence(seed, spawn_key=(k, restart))``).
    n_init : int, default 4
        Initialisations per k >= 2; the fit with the largest likelihood is kept.

    Returns
    -------
    JointSets2D

    Raises
    ------
    ValueError
        No angle with a positive weight; ``n_sets`` larger than the number of distinct fitted angles
        (or than 1 when they are all equal); bad weights (the message names ``weights``).

    Notes
    -----
    On doubled angles :math:`x_i = 2\theta_i` with weights :math:`w_i` scaled to
    :math:`\sum w_i = n`, the mixture density is
    :math:`f(x) = \sum_k \pi_k \exp(\kappa_k \cos(x - \mu_k)) / (2\pi I_0(\kappa_k))`.
    EM (Banerjee et al. 2005, §4 for p = 2) alternates posteriors
    :math:`r_{ik} \propto \pi_k f_k(x_i)` with the weighted updates
    :math:`\pi_k = \sum_i w_i r_{ik} / n`,
    :math:`\mu_k = \arg \sum_i w_i r_{ik} e^{i x_i}`,
    :math:`\bar R_k = |\sum_i w_i r_{ik} e^{i x_i}| / \sum_i w_i r_{ik}` and
    :math:`\kappa_k = A_1^{-1}(\bar R_k)`, :math:`A_1 = I_1/I_0`, solved by Newton's method from
    Banerjee's approximation :math:`\bar R (2 - \bar R^2)/(1 - \bar R^2)`. The log-likelihood of the
    axial angles (radians) adds :math:`n \ln 2` to that of the doubled ones (docs/fractures.md §4,
    eqs. (4.1)-(4.6)).

    Initialisation is k-means++ on the circle (distance :math:`1 - \cos(x - c)`, seeds drawn with
    probability proportional to weight × distance; Arthur & Vassilvitskii 2007) followed by a few
    weighted circular k-means steps; it is reproducible from ``seed``.

    Capping κ keeps EM away from the unbounded likelihood of a set collapsed onto one angle, and keeps
    all-parallel traces finite. Length weights are scaled to sum to Kish's effective sample size
    :math:`n_{eff} = (\sum w_i)^2 / \sum w_i^2` (Kish 1965), which is also the n of the BIC penalty
    :math:`(3k - 1) \ln n_{eff}`: counting every trace as an independent angle while long traces
    dominate the likelihood over-fits (on the bundled 3-set sample it split a set in two).

    References
    ----------
    .. [1] Banerjee, A., Dhillon, I. S., Ghosh, J., Sra, S. (2005). Clustering on the unit hypersphere
       using von Mises-Fisher distributions. JMLR 6, 1345-1382.
    .. [2] Mardia, K. V., Jupp, P. E. (2000). Directional Statistics. Wiley, §9.3, §10.3.
    .. [3] Arthur, D., Vassilvitskii, S. (2007). k-means++: the advantages of careful seeding. SODA.
    .. [4] Schwarz, G. (1978). Estimating the dimension of a model. Ann. Stat. 6, 461-464.
    .. [5] Kish, L. (1965). Survey Sampling. Wiley, §11.7 (effective sample size of weighted data).

    Examples
    --------
    >>> fit = fit_axial_mixture([178.0, 179.0, 1.0, 2.0, 88.0, 90.0, 92.0])
    >>> fit.n_sets, fit.mean_angle_deg.round(6).tolist(), fit.membership.tolist()
    (2, [0.0, 90.0], [0, 0, 0, 0, 1, 1, 1])
    """
    angles = _as_angles(angles_deg)
    w = _as_weights(weights, angles.size)
    resolution = math.radians(
        _real_at_least(resolution_deg, "resolution_deg", "angular resolution in degrees", above_zero=True)
    )
    kappa_max = 1.0 / (4.0 * resolution * resolution)
    max_sets, n_init, seed = check_options(max_sets, n_init, seed)
    directed = np.isfinite(angles)
    fitted = directed & (w > 0.0)
    n_fit = int(np.count_nonzero(fitted))
    if n_fit == 0:
        raise ValueError("no angle to fit: every trace lacks a direction (zero length) or has weight 0")
    x = np.radians(2.0 * angles[fitted]) % (2.0 * np.pi)
    # Kish's effective sample size: length weights make long traces count more, so the data carry
    # (sum w)^2 / sum w^2 <= n independent angles; the likelihood and the BIC penalty both use it
    n_eff = float(w[fitted].sum() ** 2 / np.sum(w[fitted] ** 2))
    wf = w[fitted] * (n_eff / w[fitted].sum())
    n_distinct = np.unique(np.round(x, 12)).size
    candidates = candidate_set_counts(n_sets, max_sets, n_distinct, "distinct trace angle(s) can be fitted")
    data = _Angles(x, wf, kappa_max)
    fit, bic, _ = fit_mixture(data, x.size, candidates, seed, n_init, lambda k: 3 * k - 1, n_eff)
    return _result(angles, directed, fit.components, fit.log_likelihood + n_eff * math.log(2.0),
                   fit.converged, bic, "given" if n_sets is not None else "bic", kappa_max)


def _as_angles(value: Any) -> np.ndarray:
    array = np.asarray(value)
    if array.dtype.kind not in "iuf":
        raise TypeError(f"angles_deg must hold real numbers (degrees), got dtype {array.dtype}")
    if array.ndim > 1:
        raise ValueError(f"angles_deg must be 1-D (one angle per trace), got shape {array.shape}")
    array = array.astype(np.float64).reshape(-1)  # a copy: the caller's array is never touched
    if np.isinf(array).any():
        raise ValueError("angles_deg must be finite or NaN (no direction), got inf")
    return array


def _as_weights(value: Any, n: int) -> np.ndarray:
    if value is None:
        return np.ones(n)
    array = np.asarray(value)
    if array.dtype.kind not in "iuf":
        raise TypeError(f"weights must hold real numbers (e.g. trace lengths), got dtype {array.dtype}")
    if array.shape != (n,):
        raise ValueError(f"weights must have one value per angle ({n}), got shape {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array) | (array < 0))
    if bad.size:
        raise ValueError(f"weights must be finite and >= 0; bad at indices {bad[:10].tolist()}")
    return array.astype(np.float64)


# -- the von Mises law on doubled angles ------------------------------------------------------


def _a1(kappa: np.ndarray) -> np.ndarray:
    """Mean resultant length of a von Mises law, I1(κ)/I0(κ), overflow-free (scaled Bessel functions)."""
    return i1e(kappa) / i0e(kappa)


def _a1_slope(kappa: np.ndarray, a: np.ndarray) -> np.ndarray:
    """A1'(κ) = 1 - A1/κ - A1², from I0' = I1 and I1' = I0 - I1/κ; its limit at κ = 0 is 1/2."""
    small = kappa < 1e-8
    return np.where(small, 0.5, 1.0 - a / np.where(small, 1.0, kappa) - a * a)


def _a1_inverse(rbar: np.ndarray, kappa_max: float) -> np.ndarray:
    """κ with A1(κ) = R̄, in [0, kappa_max]: Banerjee et al. (2005, §4) start, then Newton steps.

    Limits: R̄ -> 0 gives κ ≈ 2R̄ (A1(κ) ≈ κ/2); R̄ >= A1(kappa_max) gives kappa_max (no 1 - R̄² → 0).
    """
    return kappa_from_rbar(rbar, kappa_max, 2, _a1, _a1_slope)


class _Angles:
    """Doubled angles x with their weights: the von Mises mixture model that the shared EM fits.

    Holds the sines and cosines every EM step reuses.
    """

    def __init__(self, x: np.ndarray, w: np.ndarray, kappa_max: float = np.inf) -> None:
        self.x, self.w = x, w
        self.weights = w
        self.kappa_max = kappa_max
        self.tolerance = _TOL * w.sum()
        self.cos, self.sin = np.cos(x), np.sin(x)
        self.cos_half, self.sin_half = np.cos(0.5 * x), np.sin(0.5 * x)

    def log_densities(self, components: Components) -> np.ndarray:
        return _log_densities(self, components.mean, components.kappa, components.weight)

    def m_step(self, post: np.ndarray, previous: Components | None = None) -> Components | None:
        """Weighted M-step (the previous components are not needed on the circle)."""
        mass = self.w[:, None] * post
        n_k = mass.sum(axis=0)
        if np.any(n_k <= 1e-9 * self.w.sum()):
            return None  # a set emptied
        # sums written out, not BLAS products: a threaded OpenBLAS ddot / gemv on 10^4 numbers waits
        # for its threads, up to ~10 ms per call on a busy machine against ~10 µs here
        c = (self.cos[:, None] * mass).sum(axis=0)
        s = (self.sin[:, None] * mass).sum(axis=0)
        mu = np.arctan2(s, c) % (2.0 * np.pi)
        rbar = np.minimum(np.hypot(c, s) / n_k, 1.0)
        return Components(mu, _a1_inverse(rbar, self.kappa_max), n_k / n_k.sum(), rbar)

    def initial_labels(self, k: int, rng: np.random.Generator) -> np.ndarray | None:
        return _kmeans_pp(self.x, self.w, k, rng)


def _log_densities(data: _Angles, mu: np.ndarray, kappa: np.ndarray, pi: np.ndarray) -> np.ndarray:
    """(n, k): log π_k + log f(x_i; μ_k, κ_k) on the doubled-angle circle, overflow-free.

    log f = κ (cos d - 1) - log(2π) - log(i0e(κ)), from I0(κ) = i0e(κ) e^κ, with
    cos d - 1 = -2 sin²(d/2) and sin(d/2) = sin(x/2) cos(μ/2) - cos(x/2) sin(μ/2): the rounding error
    of sin(d/2) is absolute (~1e-16), so κ sin²(d/2) stays exact to ~κ 1e-32 as d -> 0, where
    κ (cos d - 1) would carry an error of ~κ 1e-16.
    """
    half = np.outer(data.sin_half, np.cos(0.5 * mu)) - np.outer(data.cos_half, np.sin(0.5 * mu))
    return (np.log(pi) - _LOG_2PI - np.log(i0e(kappa))) - 2.0 * kappa * half * half


def _kmeans_pp(x: np.ndarray, w: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray | None:
    """Hard labels from k-means++ seeding and weighted circular k-means; None with < k distinct angles."""
    centres = [x[rng.choice(x.size, p=w / w.sum())]]
    for _ in range(1, k):
        dist = np.min(1.0 - np.cos(x[:, None] - np.array(centres)[None, :]), axis=1)
        mass = w * np.maximum(dist, 0.0)
        if mass.sum() <= 0.0:
            return None
        centres.append(x[rng.choice(x.size, p=mass / mass.sum())])
    centres = np.array(centres)
    for _ in range(10):
        labels = np.argmax(np.cos(x[:, None] - centres[None, :]), axis=1)
        c = np.bincount(labels, weights=w * np.cos(x), minlength=k)
        s = np.bincount(labels, weights=w * np.sin(x), minlength=k)
        if np.any(np.bincount(labels, weights=w, minlength=k) <= 0.0):
            return None
        centres = np.arctan2(s, c)
    return labels


def _result(angles, directed, components: Components, loglik, converged, bic, selected_by,
            kappa_max) -> JointSets2D:
    mu, kappa, pi, rbar = components.mean, components.kappa, components.weight, components.rbar
    mean = np.degrees(mu) / 2.0
    mean[mean >= 180.0] = 0.0  # mu rounded up to 2 pi
    order = np.argsort(mean, kind="stable")
    mean, mu, kappa, pi, rbar = mean[order], mu[order], kappa[order], pi[order], rbar[order]
    k = mu.size
    posterior = np.zeros((angles.size, k))
    x = np.radians(2.0 * angles[directed]) % (2.0 * np.pi)
    log_p = _log_densities(_Angles(x, np.ones(x.size)), mu, kappa, pi)
    posterior[directed] = posteriors(log_p)
    membership = np.full(angles.size, -1, dtype=np.int64)
    membership[directed] = np.argmax(posterior[directed], axis=1)
    with np.errstate(divide="ignore"):  # R̄ = 0 (no preferred direction) gives an infinite spread
        spread = np.degrees(0.5 * np.sqrt(-2.0 * np.log(rbar))) + 0.0  # + 0.0 turns -0.0 into 0.0
    return JointSets2D(
        mean_angle_deg=mean,
        spread_deg=spread,
        kappa=kappa,
        kappa_capped=kappa >= kappa_max,
        weight=pi,
        count=np.bincount(membership[directed], minlength=k).astype(np.int64),
        membership=membership,
        posterior=posterior,
        angle_deg=angles,
        log_likelihood=loglik,
        bic=bic,
        selected_by=selected_by,
        kappa_max=kappa_max,
        converged=converged,
    )
