"""Disk radius distributions fitted to censored trace lengths in convex windows (maximum likelihood).

A trace map in a window sees three kinds of trace (classified by :func:`censored_traces`):

=========  ==============================  ===============================================
class      ends inside the window          what the window shows
=========  ==============================  ===============================================
2          both                            the whole trace length l
1          one (the other on the boundary) a piece c of a trace that is longer than c
0          none (crosses the window)       a chord c of a trace that covers it
=========  ==============================  ===============================================

Likelihood (Laslett 1982, eqs. 3.1-3.4)
---------------------------------------
For a stationary Poisson process of segments on a plane with length density h, length independent
of direction, observed in a convex window of area A, the log-likelihood of the lengths is, up to
terms that do not depend on h,

.. math::
    \\ell(h) = \\sum_{\\text{class 2}} \\ln h(l_i) + \\sum_{\\text{class 1}} \\ln S(c_i)
             + \\sum_{\\text{class 0}} \\ln G(c_i) - N \\ln(A + \\mu B)

with S(l) = ∫_l^∞ h the survival function, G(c) = ∫_c^∞ S = ∫ (l - c)₊ h(l) dl, μ = ∫ l h the mean
length, N the number of traces seen and B = E_θ[b(θ)] the mean width of the window across the
traces (b(θ) = the window's extent normal to direction θ; A + l b(θ) is the area of the window
dilated by a segment of length l, which is where a trace of that length must be centred to be seen).
The Poisson rate has been maximised out (λ̂ = N / (A + μB)). B is estimated from the observed
directions with Horvitz-Thompson weights 1/(A + μ b(θ_i)), because long traces and traces across
the window's long side are over-represented.

Traces of disks (docs/fractures.md §10.2-§10.3)
-----------------------------------------------
A disk of radius r cut by a plane at a uniformly distributed offset leaves a chord l = 2√(r² − s²),
s ~ U(0, r); the disks cut have radii size-biased by r, independent of orientation. So the trace
lengths of disks with radius density g are

.. math::
    h(l) = \\frac{1}{E[r]} \\int_{l/2}^{\\infty} g(r) \\frac{l/4}{\\sqrt{r^2 - l^2/4}}\\,dr, \\quad
    S(l) = \\frac{1}{E[r]} \\int_{l/2}^{\\infty} g(r) \\sqrt{r^2 - l^2/4}\\,dr,

    G(c) = \\frac{1}{E[r]} \\int_{c/2}^{\\infty} g(r)\\, r^2
           \\left(\\tfrac{\\pi}{2} - \\varphi - \\sin\\varphi\\cos\\varphi\\right) dr,
    \\quad \\sin\\varphi = \\frac{c}{2r},

with μ = π E[r²] / (2 E[r]). The radius parameters are fitted directly (no trace-length law in
between, so the power-law relation a₂ = a₃ − 1 and the distortion of the trace law below 2 r_min are
both built in). The integrals use r = (l/2) cosh t, which removes the inverse-square-root singularity,
and Gauss-Legendre quadrature in t (:data:`N_NODES` nodes).

Families: ``power_law`` (α and r_min free, r_max fixed — the longest radius is not identifiable
from traces shorter than the window), ``lognormal`` (mean and sd), ``exponential`` (scale). Each is
maximised with Nelder-Mead on log parameters; standard deviations come from the inverse of a
finite-difference Hessian of −ℓ (delta method back to the natural parameters); candidates are
compared by AIC = 2k − 2ℓ.

References
----------
.. [Las82] Laslett, G. M. (1982). Censoring and edge effects in areal and line transect sampling of
   rock joint traces. Mathematical Geology 14(2), 125-140. doi:10.1007/BF01083948
.. [Mau98] Mauldon, M. (1998). Estimating mean fracture trace length and density from observations
   in convex windows. Rock Mechanics and Rock Engineering 31(4), 201-216. doi:10.1007/s006030050021
.. [Zha02] Zhang, L., Einstein, H. H., Dershowitz, W. S. (2002). Stereological relationship between
   trace length and size distribution of elliptical discontinuities. Géotechnique 52(6), 419-433.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike

from .generation import size_upper_bound
from .orientation import _as_scalar
from .sizes import ExponentialSize, LognormalSize, PowerLawSize
from .tracemap import TraceMap

__all__ = ["CensoredTraces", "SizeFit", "censored_traces", "fit_sizes", "trace_length_functions"]

#: Gauss-Legendre nodes of the radius integrals (the integrands are smooth in t = arccosh(2r/l);
#: 96 nodes give the closed-form mean trace length to 1e-6 relative for the families below).
N_NODES = 96
#: Size families that :func:`fit_sizes` knows.
FAMILIES = ("power_law", "lognormal", "exponential")
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(N_NODES)
#: −ℓ returned for parameters outside a family's domain (finite, so the simplex arithmetic stays finite).
_PENALTY = 1e300
#: Points of the first r_min grid of the power-law profile likelihood (then refined twice by 9 points;
#: α is searched to 1e-4 in ln α at each, far below its statistical error).
_R_MIN_GRID = 25
#: Search range of the power-law exponent α (the density of radii ∝ r^(−α)). An α that ends
#: within 0.1 % of either end is a boundary solution: the likelihood keeps rising beyond it, the
#: traces do not bound α (too few, or of nearly one length), and the fit says so (``SizeFit.note``).
ALPHA_RANGE = (0.02, 20.0)

#: Log-parameter step of the power law's Hessian (see :func:`_profile_power_law`).
_SMOOTH_STEP = 0.05


@dataclass(frozen=True, eq=False)
class CensoredTraces:
    """Trace lengths seen in one convex window, with the number of ends inside it.

    Attributes
    ----------
    length_m : (n,) float64
        Length of each trace inside the window, metres, > 0.
    ends_inside : (n,) int64
        0, 1 or 2 trace ends strictly inside the window (the class of the module docstring).
    angle_rad : (n,) float64
        Direction of each trace in the window's frame, radians in [0, π).
    window_xy_m : (k, 2) float64
        The convex window polygon (open ring).
    """

    length_m: np.ndarray
    ends_inside: np.ndarray
    angle_rad: np.ndarray
    window_xy_m: np.ndarray

    def __post_init__(self) -> None:
        length = np.asarray(self.length_m, dtype=np.float64).ravel()
        ends = np.asarray(self.ends_inside).ravel()
        angle = np.asarray(self.angle_rad, dtype=np.float64).ravel()
        ring = np.asarray(self.window_xy_m, dtype=np.float64)
        if not (length.size == ends.size == angle.size):
            raise ValueError(f"length_m, ends_inside and angle_rad must have one value per trace, got "
                             f"{length.size}, {ends.size}, {angle.size}")
        if not (np.isfinite(length).all() and (length > 0).all()):
            raise ValueError("length_m must be finite and > 0 for every trace (metres inside the window)")
        if not np.isin(ends, (0, 1, 2)).all():
            raise ValueError("ends_inside must be 0, 1 or 2 for every trace")
        if not np.isfinite(angle).all():
            raise ValueError("angle_rad must be finite")
        polygon = _convex_window(ring, "window_xy_m")
        for name, value in (("length_m", length), ("ends_inside", ends.astype(np.int64)),
                            ("angle_rad", np.mod(angle, np.pi)),
                            ("window_xy_m", np.asarray(polygon.exterior.coords)[:-1])):
            value = np.array(value, copy=True)
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def n_traces(self) -> int:
        return int(self.length_m.size)

    @functools.cached_property
    def area_m2(self) -> float:
        """Window area A, m²."""
        return float(shapely.Polygon(self.window_xy_m).area)

    @functools.cached_property
    def trace_width_m(self) -> np.ndarray:
        """b(θ_i) of every trace, (n,) (read-only; computed once, the likelihood needs it each step)."""
        width = self.width_m(self.angle_rad)
        width.setflags(write=False)
        return width

    def width_m(self, angle_rad: ArrayLike) -> np.ndarray:
        """b(θ): extent of the window normal to direction θ (metres); A + l b(θ) = dilated area."""
        theta = np.asarray(angle_rad, dtype=np.float64)
        normal = np.stack([-np.sin(theta), np.cos(theta)], axis=-1)
        proj = normal @ self.window_xy_m.T
        return proj.max(axis=-1) - proj.min(axis=-1)

    def counts(self) -> dict:
        """Number of traces in each class: ``{"complete": .., "one_end": .., "crossing": ..}``."""
        return {"complete": int(np.sum(self.ends_inside == 2)), "one_end": int(np.sum(self.ends_inside == 1)),
                "crossing": int(np.sum(self.ends_inside == 0))}


def _convex_window(ring: np.ndarray, name: str) -> shapely.Polygon:
    if ring.ndim != 2 or ring.shape[1] != 2 or ring.shape[0] < 3 or not np.isfinite(ring).all():
        raise ValueError(f"{name} must be a (k, 2) ring of finite (u, v) metres with k >= 3, got shape {ring.shape}")
    polygon = shapely.Polygon(ring)
    if not polygon.is_valid or polygon.area <= 0:
        raise ValueError(f"{name} must be a valid polygon of non-zero area")
    if polygon.convex_hull.area - polygon.area > 1e-9 * polygon.area:
        raise ValueError(f"{name} must be convex: the censored-length likelihood needs a convex window "
                         f"(use its convex part, or several convex windows)")
    return shapely.Polygon(shapely.get_coordinates(polygon.exterior)).normalize()


def censored_traces(trace_map: TraceMap, *, tolerance_m: float | None = None,
                    selection: ArrayLike | None = None) -> CensoredTraces:
    """Classify the traces of a map by how many of their ends lie strictly inside its window.

    Parameters
    ----------
    trace_map : TraceMap
        Straight or nearly straight traces with a convex ``window_xy_m``; each trace is reduced to
        its end points (first and last vertex) for its direction, and clipped to the window for its
        length.
    tolerance_m : float, optional
        An end closer than this to the window boundary counts as censored. Default 1e-9 times the
        window's diameter (virtual sections clip exactly onto the boundary); give the digitising
        accuracy for field maps.
    selection : (n_traces,) bool or int array_like, optional
        Traces to keep (e.g. one joint set). Default all.

    Returns
    -------
    CensoredTraces
        Traces with a non-zero length inside the window.

    Examples
    --------
    >>> tm = TraceMap.from_polylines([[(1, 1), (2, 1)], [(0, 2), (3, 2)], [(-1, 3), (4, 3)]],
    ...                              window=[(0, 0), (4, 0), (4, 4), (0, 4)])
    >>> censored_traces(tm).ends_inside.tolist()
    [2, 1, 0]
    """
    if not isinstance(trace_map, TraceMap):
        raise TypeError(f"trace_map must be a TraceMap, got {type(trace_map).__name__}")
    if trace_map.window_xy_m is None:
        raise ValueError("trace_map has no window: the censored-length fit needs the sampling window polygon")
    polygon = _convex_window(np.asarray(trace_map.window_xy_m), "trace_map window")
    ring = np.asarray(polygon.exterior.coords)[:-1]
    diameter = float(np.max(np.linalg.norm(ring[:, None] - ring[None], axis=-1)))
    tol = 1e-9 * diameter if tolerance_m is None else _as_scalar(tolerance_m, "tolerance_m", low=0.0,
                                                                  what="boundary tolerance in metres")
    offsets = trace_map.offsets
    keep = np.ones(trace_map.n_traces, dtype=bool)
    if selection is not None:
        keep = np.zeros(trace_map.n_traces, dtype=bool)
        keep[np.asarray(selection)] = True
    idx = np.flatnonzero(keep & (np.diff(offsets) >= 2))
    first = trace_map.xy_m[offsets[idx]]
    last = trace_map.xy_m[offsets[idx + 1] - 1]
    boundary = polygon.exterior
    inside = np.zeros((idx.size, 2), dtype=bool)
    for k, ends in enumerate((first, last)):
        points = shapely.points(ends)
        inside[:, k] = shapely.contains_xy(polygon, ends[:, 0], ends[:, 1]) & \
            (shapely.distance(points, boundary) > tol)
    clipped = shapely.length(shapely.intersection(trace_map.to_shapely()[idx], polygon))
    delta = last - first
    angle = np.mod(np.arctan2(delta[:, 1], delta[:, 0]), np.pi)
    seen = clipped > 0
    return CensoredTraces(clipped[seen], inside.sum(axis=1)[seen], angle[seen], ring)


# -- trace-length functions of a disk radius law --------------------------------------------------


def _radius_integral(size, half: np.ndarray, integrand, r_hi: float) -> np.ndarray:
    """∫_{r >= half} g(r) k(r) dr via r = half·cosh t, Gauss-Legendre in t; (n,) values.

    ``integrand(r, half, t)`` returns k(r) · dr/dt (dr/dt = half sinh t), which is smooth in t;
    ``r_hi`` is the largest radius (:func:`~rockmass.dfn.generation.size_upper_bound`).
    """
    r_lo = float(getattr(size, "r_min_m", 0.0))
    out = np.zeros(half.size)
    ok = half < r_hi
    if not ok.any():
        return out
    h = half[ok]
    t0 = np.arccosh(np.maximum(1.0, r_lo / h))
    t1 = np.arccosh(r_hi / h)
    mid, rad = 0.5 * (t1 + t0), 0.5 * (t1 - t0)
    t = mid[:, None] + rad[:, None] * _NODES[None, :]
    r = h[:, None] * np.cosh(t)
    dens = size.pdf(np.clip(r, r_lo, r_hi)).reshape(r.shape)
    values = dens * integrand(r, h[:, None], t)
    out[ok] = rad * (values @ _WEIGHTS)
    return out


# with r = half cosh t: sqrt(r² - half²) = half sinh t and dr = half sinh t dt, so
# h: g (l/4) / sqrt(r² - l²/4) dr = g half/2 dt;  S: g sqrt(r² - l²/4) dr = g (half sinh t)² dt;
# G: g r² (π/2 - φ - sin φ cos φ) dr, sin φ = half / r.
def _h_integrand(r, hh, t):
    return 0.5 * hh + 0.0 * t


def _s_integrand(r, hh, t):
    return (hh * np.sinh(t)) ** 2


def _g_integrand(r, hh, t):
    phi = np.arcsin(np.clip(hh / r, 0.0, 1.0))
    return r * r * (0.5 * np.pi - phi - np.sin(phi) * np.cos(phi)) * hh * np.sinh(t)


_INTEGRANDS = (_g_integrand, _s_integrand, _h_integrand)   # indexed by the number of ends inside


def _check_family_size(size) -> None:
    if not isinstance(size, (PowerLawSize, LognormalSize, ExponentialSize)):
        raise TypeError(f"size must be a PowerLawSize, LognormalSize or ExponentialSize, got {type(size).__name__}")


def trace_length_functions(size, lengths_m: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Density h(l), survival S(l) and G(l) = ∫_l^∞ S of the trace lengths of disks (module docstring).

    Parameters
    ----------
    size : PowerLawSize, LognormalSize or ExponentialSize
        Disk radius distribution.
    lengths_m : (n,) array_like of float
        Trace lengths l > 0, metres.

    Returns
    -------
    h, S, G : (n,) float64
        In 1/m, dimensionless and metres. S(0+) = 1 and G(0+) = π E[r²] / (2 E[r]).

    Examples
    --------
    >>> size = PowerLawSize(1.0, 10.0, 2.5)
    >>> h, s, g = trace_length_functions(size, [1e-9])
    >>> round(float(g[0]) / (np.pi * size.moment(2) / (2 * size.mean())), 6)
    1.0
    """
    _check_family_size(size)
    half = np.asarray(lengths_m, dtype=np.float64).ravel() / 2.0
    r_hi, mean_r = size_upper_bound(size), size.mean()
    h, s, g = (_radius_integral(size, half, f, r_hi) / mean_r for f in (_h_integrand, _s_integrand, _g_integrand))
    return h, s, g


def mean_trace_length_m(size) -> float:
    """μ = π E[r²] / (2 E[r]) (docs/fractures.md §10.2, eq. (10.6); Zhang et al. 2002)."""
    return float(np.pi * size.moment(2.0) / (2.0 * size.mean()))


# -- the fit ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SizeFit:
    """A disk radius law fitted to censored trace lengths.

    Attributes
    ----------
    family : str
        ``"power_law"``, ``"lognormal"`` or ``"exponential"``.
    params : dict of str to float
        The natural parameters (``alpha``, ``r_min_m``, ``r_max_m``; ``mean_m``, ``sd_m``; ``scale_m``).
    sd : dict of str to float or None
        Standard deviation of each free parameter (None where the Hessian is not positive definite).
    size : SizeDistribution or None
        The fitted distribution (None when ``ok`` is False).
    log_likelihood : float
        ℓ at the fit (module docstring; −inf when ``ok`` is False).
    aic : float
        2k − 2ℓ (k = free parameters).
    mean_trace_length_m : float
        π E[r²]/(2 E[r]) of the fitted law.
    n_traces : int
    counts : dict
        Traces per class (complete, one_end, crossing), summed over windows.
    ok : bool
    reason : str
        Why the fit failed ('' when ``ok``).
    note : str
        A caveat of a fit that is ``ok`` (e.g. a power-law exponent at the end of its search range,
        :data:`ALPHA_RANGE`: the traces do not bound it), '' when there is none.
    """

    family: str
    params: dict
    sd: dict
    size: object
    log_likelihood: float
    aic: float
    mean_trace_length_m: float
    n_traces: int
    counts: dict
    ok: bool = True
    reason: str = ""
    note: str = ""

    def as_dict(self) -> dict:
        """JSON-ready (no NaN: undefined numbers are None)."""
        def clean(v):
            return None if v is None or not np.isfinite(v) else float(v)
        return {"family": self.family, "params": {k: clean(v) for k, v in self.params.items()},
                "sd": {k: clean(v) for k, v in self.sd.items()}, "log_likelihood": clean(self.log_likelihood),
                "aic": clean(self.aic), "mean_trace_length_m": clean(self.mean_trace_length_m),
                "n_traces": self.n_traces, "counts": dict(self.counts), "ok": self.ok, "reason": self.reason,
                "note": self.note}


def _family(name: str, r_max: float):
    """(parameter names, natural -> size, start vector from the mean observed length)."""
    if name == "power_law":
        return (("alpha", "r_min_m"), lambda p: PowerLawSize(p[1], r_max, p[0]),
                lambda m: np.array([2.0, min(0.3 * m, 0.5 * r_max)]))
    if name == "lognormal":
        return (("mean_m", "sd_m"), lambda p: LognormalSize(p[0], p[1]),
                lambda m: np.array([0.5 * m, 0.3 * m]))
    if name == "exponential":
        return (("scale_m",), lambda p: ExponentialSize(p[0]), lambda m: np.array([0.4 * m]))
    raise ValueError(f"family must be one of {', '.join(FAMILIES)}, got {name!r}")


def _log_likelihood(size, samples: Sequence[CensoredTraces]) -> float:
    """ℓ of the module docstring, summed over windows; each trace needs only its class's function."""
    mu = mean_trace_length_m(size)
    r_hi, mean_r = size_upper_bound(size), size.mean()
    total = 0.0
    for sample in samples:
        if sample.n_traces == 0:
            continue
        for ends, integrand in enumerate(_INTEGRANDS):
            mask = sample.ends_inside == ends
            if mask.any():
                values = _radius_integral(size, sample.length_m[mask] / 2.0, integrand, r_hi) / mean_r
                if not (values > 0).all():
                    return -np.inf
                total += float(np.sum(np.log(values)))
        area = sample.area_m2
        width = sample.trace_width_m
        w = 1.0 / (area + mu * width)                   # Horvitz-Thompson weights of the directions
        mean_width = float(np.sum(w * width) / np.sum(w))
        total -= sample.n_traces * np.log(area + mu * mean_width)
    return total


def _hessian(fun, x: np.ndarray, step: float = 1e-3) -> np.ndarray:
    """Central finite-difference Hessian of ``fun`` at ``x`` (x on a log scale, so ``step`` is relative)."""
    k = x.size
    hess = np.empty((k, k))
    f0 = fun(x)
    for i in range(k):
        for j in range(i, k):
            if i == j:
                e = np.zeros(k)
                e[i] = step
                hess[i, i] = (fun(x + e) - 2 * f0 + fun(x - e)) / step ** 2
            else:
                ei, ej = np.zeros(k), np.zeros(k)
                ei[i], ej[j] = step, step
                hess[i, j] = hess[j, i] = (fun(x + ei + ej) - fun(x + ei - ej) - fun(x - ei + ej)
                                           + fun(x - ei - ej)) / (4 * step ** 2)
    return hess


def _failed(family: str, names, n: int, counts: dict, reason: str) -> SizeFit:
    return SizeFit(family, {k: float("nan") for k in names}, {k: None for k in names}, None, -np.inf, np.inf,
                   float("nan"), n, counts, ok=False, reason=reason)


def _nelder_mead(negative, x: np.ndarray, names) -> tuple[np.ndarray, float, dict]:
    """Minimise a smooth −ℓ over log parameters; sd by the inverse Hessian and the delta method."""
    from scipy.optimize import minimize

    best = None
    for _ in range(2):                                  # a restart at the optimum guards against a collapsed simplex
        res = minimize(negative, x, method="Nelder-Mead", options={"xatol": 1e-5, "fatol": 1e-6, "maxiter": 800})
        if best is None or res.fun <= best.fun:
            best, x = res, res.x
    sd = {k: None for k in names}
    hess = _hessian(negative, best.x)
    if np.isfinite(hess).all():
        try:
            cov = np.linalg.inv(hess)
            if (np.linalg.eigvalsh(0.5 * (cov + cov.T)) > 0).all():
                p = np.exp(best.x)
                sd = {k: float(p[i] * np.sqrt(cov[i, i])) for i, k in enumerate(names)}   # delta method
        except np.linalg.LinAlgError:
            pass
    return best.x, float(best.fun), sd


def _power_law_at_r_min(samples: Sequence[CensoredTraces], r_min: float, r_max: float):
    """−ℓ(ln α) of a power law at fixed r_min and r_max, the α-free part of every integral cached.

    With r_min, r_max fixed the quadrature nodes r_ik and the class integrands K_ik do not depend on
    α, and g(r) = (r_min/r)^α / (r Λ exprel(−αΛ)), so each integral is
    Σ_k w_k K_ik / r_ik · exp(α ln(r_min/r_ik)) / (Λ exprel(−αΛ)): one exp per node and step.
    Equals :func:`_log_likelihood` of ``PowerLawSize(r_min, r_max, α)`` (tested).
    """
    from scipy.special import exprel

    lam = float(np.log(r_max) - np.log(r_min))
    parts = []          # (weights (n, N), log ratios (n, N)) per window and class, plus per window data
    windows = []
    for sample in samples:
        if sample.n_traces == 0:
            continue
        for ends, integrand in enumerate(_INTEGRANDS):
            half = sample.length_m[sample.ends_inside == ends] / 2.0
            if half.size == 0:
                continue
            if (half >= r_max).any():
                return lambda log_alpha: _PENALTY        # a trace longer than 2 r_max: h = 0
            t0 = np.arccosh(np.maximum(1.0, r_min / half))
            t1 = np.arccosh(r_max / half)
            mid, rad = 0.5 * (t1 + t0), 0.5 * (t1 - t0)
            t = mid[:, None] + rad[:, None] * _NODES[None, :]
            r = half[:, None] * np.cosh(t)
            base = integrand(r, half[:, None], t) / r * _WEIGHTS[None, :] * rad[:, None]
            parts.append((base, np.log(r_min / np.clip(r, r_min, r_max))))
        windows.append((sample.n_traces, sample.area_m2, sample.trace_width_m))

    def negative(log_alpha: float) -> float:
        alpha = float(np.exp(log_alpha))
        try:
            size = PowerLawSize(r_min, r_max, alpha)
        except ValueError:
            return _PENALTY
        scale = 1.0 / (lam * exprel(-alpha * lam) * size.mean())
        total = 0.0
        for base, log_ratio in parts:
            values = np.sum(base * np.exp(alpha * log_ratio), axis=1) * scale
            if not (values > 0).all():
                return _PENALTY
            total += float(np.sum(np.log(values)))
        mu = mean_trace_length_m(size)
        for n, area, width in windows:
            w = 1.0 / (area + mu * width)
            total -= n * np.log(area + mu * float(np.sum(w * width) / np.sum(w)))
        return -total

    return negative


def _profile_power_law(negative, samples: Sequence[CensoredTraces], lengths: np.ndarray,
                       r_max: float) -> tuple[np.ndarray, float, dict]:
    """Power law: profile −ℓ over r_min on a log grid, α by a bounded 1-D search at each r_min.

    ℓ has a square-root cusp in r_min at every half trace length (h(l) jumps in slope when r_min
    crosses l/2), so a simplex stalls on it; a grid of :data:`_R_MIN_GRID` points from 1 % of the
    median length to r_max/2, refined twice around the best point, does not. The covariance of
    (ln α, ln r_min) is the inverse of a finite-difference Hessian with steps of :data:`_SMOOTH_STEP`
    (5 % of each parameter), wide enough to average over the cusps (≈ 0.1 in ℓ) yet small against
    the statistical scale; sd by the delta method, marginal over the other parameter.
    """
    from scipy.optimize import minimize_scalar

    def inner(log_rmin: float) -> tuple[float, float]:
        res = minimize_scalar(_power_law_at_r_min(samples, float(np.exp(log_rmin)), r_max),
                              bounds=tuple(np.log(ALPHA_RANGE)), method="bounded", options={"xatol": 1e-4})
        return float(res.x), float(res.fun)

    lo = np.log(0.01 * float(np.median(lengths)))
    hi = np.log(0.5 * r_max)
    grid = np.linspace(lo, min(hi, np.log(2.0 * float(np.max(lengths)))), _R_MIN_GRID)
    table = {}
    for _ in range(3):
        for g in grid:
            if g not in table:
                table[g] = inner(g)
        keys = np.array(sorted(table))
        k = int(np.argmin([table[g][1] for g in keys]))
        left, right = keys[max(k - 1, 0)], keys[min(k + 1, keys.size - 1)]
        grid = np.linspace(left, right, 9)
    keys = np.array(sorted(table))
    funs = np.array([table[g][1] for g in keys])
    k = int(np.argmin(funs))
    log_rmin, (log_alpha, fun) = keys[k], table[keys[k]]
    x = np.array([log_alpha, log_rmin])
    sd = {"alpha": None, "r_min_m": None}
    hess = _hessian(negative, x, step=_SMOOTH_STEP)
    if np.isfinite(hess).all():
        try:
            cov = np.linalg.inv(hess)
            if (np.linalg.eigvalsh(0.5 * (cov + cov.T)) > 0).all():
                sd = {k: float(np.exp(x[i]) * np.sqrt(cov[i, i])) for i, k in enumerate(sd)}
        except np.linalg.LinAlgError:
            pass
    return x, fun, sd


def _fit_family(family: str, samples: list[CensoredTraces], r_max: float) -> SizeFit:
    names, build, start = _family(family, r_max)
    n = sum(s.n_traces for s in samples)
    counts = {k: sum(s.counts()[k] for s in samples) for k in ("complete", "one_end", "crossing")}
    if counts["complete"] + counts["one_end"] < len(names) + 1:
        return _failed(family, names, n, counts, f"{counts['complete'] + counts['one_end']} traces with an "
                       f"end inside the window; at least {len(names) + 1} are needed")
    lengths = np.concatenate([s.length_m for s in samples])

    def negative(log_p: np.ndarray) -> float:
        p = np.exp(log_p)
        try:
            size = build(p)
        except ValueError:
            return _PENALTY
        value = _log_likelihood(size, samples)
        return -value if np.isfinite(value) else _PENALTY

    if family == "power_law":
        x, fun, sd = _profile_power_law(negative, samples, lengths, r_max)
    else:
        x, fun, sd = _nelder_mead(negative, np.log(start(float(lengths.mean()))), names)
    if fun >= _PENALTY:
        return _failed(family, names, n, counts, "no parameters give a finite likelihood")
    p = np.exp(x)
    size = build(p)
    best_fun = fun
    params = {k: float(p[i]) for i, k in enumerate(names)}
    if family == "power_law":
        params["r_max_m"] = float(r_max)
    ll = -float(best_fun)
    note = ""
    if family == "power_law" and not (ALPHA_RANGE[0] * 1.001 < params["alpha"] < ALPHA_RANGE[1] / 1.001):
        note = (f"alpha {params['alpha']:.4g} is at the end of its search range "
                f"{ALPHA_RANGE[0]:g}-{ALPHA_RANGE[1]:g}: these {n} traces do not bound the power law's "
                "exponent; compare the other families' AIC or map more traces")
    return SizeFit(family, params, sd, size, ll, 2 * len(names) - 2 * ll, mean_trace_length_m(size), n, counts,
                   note=note)


def fit_sizes(samples: CensoredTraces | Sequence[CensoredTraces], *, families: Sequence[str] = FAMILIES,
              r_max_m: float = 100.0) -> dict[str, SizeFit]:
    """Maximum-likelihood disk radius laws from censored trace lengths in one or more windows.

    Parameters
    ----------
    samples : CensoredTraces or sequence of them
        The traces of one joint set, one entry per window (their log-likelihoods add).
    families : sequence of str, default all of :data:`FAMILIES`
        Candidate laws.
    r_max_m : float, default 100
        Upper truncation of the power law (fixed, metres; > 0).

    Returns
    -------
    dict of str to SizeFit
        One fit per family, in the order given, plus ``"best"``: the successful fit with the smallest
        AIC (a failed :class:`SizeFit` when none succeeded).

    Notes
    -----
    The likelihood, its source ([Las82]_) and the disk trace-length integrals are in the module
    docstring. A fit needs more traces with an end inside the window than free parameters; with
    only crossing traces the lengths are not identifiable and the fit says so (``ok=False``).

    Windows are taken as independent samples. Faces that cut the same disks (faces that meet, or
    lie closer than the largest disk diameter) share traces, so their errors are positively
    correlated and the stated sd is then too small by up to √(number of faces); the estimate itself
    stays unbiased. (Seen in development: three faces meeting at a point, fitted together, gave
    z = (α̂ − α)/sd well above 3 on a realization whose single-face z values were each about 2.)
    """
    if isinstance(samples, CensoredTraces):
        samples = [samples]
    samples = list(samples)
    if not samples or not all(isinstance(s, CensoredTraces) for s in samples):
        raise TypeError("samples must be a CensoredTraces or a non-empty sequence of them")
    r_max = _as_scalar(r_max_m, "r_max_m", low=0.0, low_open=True, what="largest disk radius in metres")
    families = list(families)
    if not families:
        raise ValueError(f"families must name at least one of {', '.join(FAMILIES)}")
    for name in families:
        _family(name, r_max)                            # raises on an unknown name
    fits = {name: _fit_family(name, samples, r_max) for name in families}
    ok = [f for f in fits.values() if f.ok]
    fits["best"] = min(ok, key=lambda f: f.aic) if ok else next(iter(fits.values()))
    return fits
