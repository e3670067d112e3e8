"""Statistics of a scanline survey: P10 (raw and Terzaghi-weighted), spacings, RQD, per joint set.

- P10 = intersections per metre of line. The Terzaghi-weighted P10 = Σ w_i / L with
  w_i = 1 / max(|cos δ_i|, sin γ) (:func:`~rockmass.dfn.terzaghi_weights`, cap γ) estimates the
  intensity of planes normal to the line, i.e. P32 of the set ([Ter65]_; docs/fractures.md §6, eqs. (6.1)-(6.2)).
- Spacings (distances between consecutive hits of the same set along the line; all hits for the
  whole line) of a Poisson network are exponential with mean 1/P10 (docs/fractures.md §2, eq. (2.2)). Both the
  exponential and the lognormal law are fitted by maximum likelihood and compared with the
  Kolmogorov–Smirnov statistic and AIC.
- RQD: [PH76]_ for a Poisson line of frequency λ and threshold t,
  RQD = 100 e^(−λt)(λt + 1); and directly from the survey, 100 × (total length of the pieces of
  line between consecutive joints, and between the ends and the first / last joint, that are at
  least t long) / L.

:func:`scanline_statistics` gathers all of it, per set and for the whole line, as a JSON-ready dict
in which undefined values are None, never NaN.

References
----------
.. [Ter65] Terzaghi, R. D. (1965). Sources of error in joint surveys. Géotechnique 15(3), 287-304.
.. [PH76] Priest, S. D., Hudson, J. A. (1976). Discontinuity spacings in rock. Int. J. Rock Mech.
   Min. Sci. 13, 135-148.
.. [Pri93] Priest, S. D. (1993). Discontinuity Analysis for Rock Engineering. Chapman & Hall
   (set spacing normal to the mean plane from spacings along a scanline).
.. [Dee64] Deere, D. U. (1964). Technical description of rock cores for engineering purposes. Rock
   Mechanics and Engineering Geology 1, 16-22.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .orientation import _as_float_array, _as_scalar, angle_between, dip_from_normal
from .scanline import Scanline
from .stereology import terzaghi_weights

__all__ = ["SpacingFit", "fit_spacings", "rqd_direct", "rqd_priest_hudson", "scanline_statistics"]

#: RQD threshold of [Dee64]_: pieces of at least 0.1 m count.
RQD_THRESHOLD_M = 0.1


def rqd_priest_hudson(p10_per_m: ArrayLike, threshold_m: float = RQD_THRESHOLD_M) -> np.ndarray:
    """Expected RQD (%) of a line crossed by a Poisson process of frequency λ ([PH76]_).

    Parameters
    ----------
    p10_per_m : float or array_like
        Frequency λ >= 0, joints per metre.
    threshold_m : float, default 0.1
        Piece length t > 0 that counts as intact, metres.

    Returns
    -------
    ndarray
        RQD = 100 e^(−λt)(λt + 1), in (0, 100]; 100 for λ = 0.

    Examples
    --------
    >>> round(float(rqd_priest_hudson(10.0)), 2)     # 100 e^-1 (1 + 1)
    73.58
    """
    lam = _as_float_array(p10_per_m, "p10_per_m")
    if (lam < 0).any():
        raise ValueError(f"p10_per_m must be >= 0 (joints per metre), got {lam[lam < 0][:5].tolist()}")
    t = _as_scalar(threshold_m, "threshold_m", low=0.0, low_open=True, what="RQD piece length in metres")
    x = lam * t
    return 100.0 * np.exp(-x) * (x + 1.0)


def rqd_direct(distance_m: ArrayLike, length_m: float, threshold_m: float = RQD_THRESHOLD_M) -> float:
    """RQD (%) measured on a line: the share of its length in pieces at least ``threshold_m`` long.

    Parameters
    ----------
    distance_m : (n,) array_like
        Joint positions along the line, metres, in [0, ``length_m``] (any order).
    length_m : float
        Line length L > 0, metres.
    threshold_m : float, default 0.1
        Smallest piece that counts, metres (> 0); a piece of exactly t counts ([Dee64]_: "10 cm and
        longer").

    Returns
    -------
    float
        100 Σ_{pieces ≥ t} piece / L, the pieces being the gaps between consecutive joints and
        between each end of the line and its nearest joint.

    Examples
    --------
    >>> rqd_direct([0.3, 0.35, 1.0], length_m=2.0)   # pieces 0.3, 0.05, 0.65, 1.0
    97.5
    """
    positions = np.sort(_as_float_array(distance_m, "distance_m").reshape(-1))
    length = _as_scalar(length_m, "length_m", low=0.0, low_open=True, what="line length in metres")
    t = _as_scalar(threshold_m, "threshold_m", low=0.0, low_open=True, what="RQD piece length in metres")
    if positions.size and (positions[0] < 0 or positions[-1] > length):
        raise ValueError(f"distance_m must be in [0, length_m = {length:g}] metres")
    pieces = np.diff(np.concatenate([[0.0], positions, [length]]))
    # compare with a relative tolerance: 0.1 written as 0.3 - 0.2 must still count
    intact = pieces >= t * (1.0 - 1e-12)
    return float(100.0 * pieces[intact].sum() / length)


@dataclass(frozen=True)
class SpacingFit:
    """Exponential and lognormal maximum-likelihood fits of spacings (see :func:`fit_spacings`).

    Undefined values are None: with fewer than 2 spacings nothing is fitted; the lognormal needs at
    least 2 positive spacings (zero spacings, joints at the same position, are left out of it).
    """

    n: int
    mean_m: float | None
    median_m: float | None
    std_m: float | None
    min_m: float | None
    max_m: float | None
    exponential_rate_per_m: float | None
    exponential_ks: float | None
    exponential_ks_p: float | None
    exponential_aic: float | None
    lognormal_mu: float | None
    lognormal_sigma: float | None
    lognormal_ks: float | None
    lognormal_ks_p: float | None
    lognormal_aic: float | None
    n_zero: int

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict (None for undefined values)."""
        return {
            "n": self.n, "mean_m": self.mean_m, "median_m": self.median_m, "std_m": self.std_m,
            "min_m": self.min_m, "max_m": self.max_m, "n_zero": self.n_zero,
            "exponential": {"rate_per_m": self.exponential_rate_per_m,
                            "mean_m": None if self.exponential_rate_per_m is None else self.mean_m,
                            "ks_statistic": self.exponential_ks, "ks_p_value": self.exponential_ks_p,
                            "aic": self.exponential_aic},
            "lognormal": {"mu_log_m": self.lognormal_mu, "sigma_log": self.lognormal_sigma,
                          "ks_statistic": self.lognormal_ks, "ks_p_value": self.lognormal_ks_p,
                          "aic": self.lognormal_aic},
            "preferred": self.preferred,
        }

    @property
    def preferred(self) -> str | None:
        """The law with the smaller AIC ("exponential" on ties), None when neither was fitted."""
        if self.exponential_aic is None:
            return None
        if self.lognormal_aic is None or self.exponential_aic <= self.lognormal_aic:
            return "exponential"
        return "lognormal"


def fit_spacings(spacings_m: ArrayLike) -> SpacingFit:
    """Fit exponential and lognormal laws to spacings by maximum likelihood, with KS and AIC.

    Parameters
    ----------
    spacings_m : (n,) array_like
        Spacings, metres, finite and >= 0.

    Returns
    -------
    SpacingFit

    Notes
    -----
    Exponential: rate λ = 1 / mean (the MLE; log L = n ln λ − λ Σ s). Lognormal: μ = mean(ln s),
    σ = sd(ln s) with divisor n (the MLEs). KS statistics are against each fitted law; their p-values
    use the parameters as if known, so they are optimistic (Lilliefors): read them as a screen, and
    compare the two laws by AIC = 2 × (number of parameters) − 2 log L.

    Examples
    --------
    >>> fit = fit_spacings([0.5, 1.0, 1.5])
    >>> fit.mean_m, round(fit.exponential_rate_per_m, 6)
    (1.0, 1.0)
    """
    from scipy import stats

    s = _as_float_array(spacings_m, "spacings_m").reshape(-1)
    if (s < 0).any():
        raise ValueError("spacings_m must be >= 0 metres")
    n = int(s.size)
    none = dict.fromkeys(("exponential_rate_per_m", "exponential_ks", "exponential_ks_p", "exponential_aic",
                          "lognormal_mu", "lognormal_sigma", "lognormal_ks", "lognormal_ks_p",
                          "lognormal_aic"))
    n_zero = int(np.count_nonzero(s == 0))
    if n == 0:
        return SpacingFit(n=0, mean_m=None, median_m=None, std_m=None, min_m=None, max_m=None,
                          n_zero=0, **none)
    summary = dict(mean_m=float(s.mean()), median_m=float(np.median(s)),
                   std_m=float(s.std(ddof=1)) if n >= 2 else None, min_m=float(s.min()),
                   max_m=float(s.max()))
    values = dict(none)
    mean = float(s.mean())
    if n >= 2 and mean > 0:
        rate = 1.0 / mean
        ks = stats.kstest(s, "expon", args=(0.0, mean))
        values.update(exponential_rate_per_m=rate, exponential_ks=float(ks.statistic),
                      exponential_ks_p=float(ks.pvalue),
                      exponential_aic=2.0 - 2.0 * (n * math.log(rate) - rate * float(s.sum())))
    positive = s[s > 0]
    if positive.size >= 2:
        logs = np.log(positive)
        mu, sigma = float(logs.mean()), float(logs.std())
        if sigma > 0:
            ks = stats.kstest(positive, "lognorm", args=(sigma, 0.0, math.exp(mu)))
            loglik = float(np.sum(stats.lognorm.logpdf(positive, sigma, 0.0, math.exp(mu))))
            values.update(lognormal_mu=mu, lognormal_sigma=sigma, lognormal_ks=float(ks.statistic),
                          lognormal_ks_p=float(ks.pvalue), lognormal_aic=4.0 - 2.0 * loglik)
    if values["lognormal_aic"] is not None and n_zero:
        values["lognormal_aic"] = None  # fitted to fewer spacings: the AICs are not comparable
    return SpacingFit(n=n, n_zero=n_zero, **summary, **values)


def _finite_or_none(value: Any) -> float | None:
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _group_statistics(scanline: Scanline, mask: np.ndarray, poles: np.ndarray, cap_deg: float,
                      threshold_m: float) -> dict[str, Any]:
    length = scanline.length_m
    n = int(np.count_nonzero(mask))
    distance = scanline.distance_m[mask]
    weights = terzaghi_weights(poles[mask], scanline.direction, min_angle_deg=cap_deg) if n else np.zeros(0)
    p10 = n / length
    capped = int(np.count_nonzero(np.isclose(weights, 1.0 / math.sin(math.radians(cap_deg)), rtol=1e-12))) if n else 0
    spacings = np.diff(distance)
    spacing = fit_spacings(spacings)
    trace = None
    if scanline.trace_length_m is not None:
        measured = scanline.trace_length_m[mask]
        measured = measured[np.isfinite(measured)]
        trace = {"n_measured": int(measured.size),
                 "mean_m": float(measured.mean()) if measured.size else None}
    return {
        "n_intersections": n,
        "p10_per_m": p10,
        "p10_terzaghi_per_m": float(weights.sum() / length),
        "n_terzaghi_capped": capped,
        "spacing_m": spacing.as_dict(),
        "spacings_m": spacings.tolist(),
        "rqd_priest_hudson_percent": float(rqd_priest_hudson(p10, threshold_m)),
        "rqd_direct_percent": rqd_direct(distance, length, threshold_m),
        "trace_length_m": trace,
    }


def scanline_statistics(scanline: Scanline, membership: ArrayLike | None = None, set_fits: Any = None, *,
                        terzaghi_cap_deg: float = 15.0,
                        rqd_threshold_m: float = RQD_THRESHOLD_M) -> dict[str, Any]:
    """P10, Terzaghi-weighted P10, spacings and RQD for the whole line and for each joint set.

    Parameters
    ----------
    scanline : Scanline
        The survey.
    membership : (n_intersections,) array_like of int, optional
        Set index (0..k-1) of each intersection, e.g. :attr:`JointSets3D.membership`; -1 leaves an
        intersection out of every set. Default None: one set holding every intersection.
    set_fits : sequence of FisherFit or None, optional
        Fisher fit of each set (:attr:`JointSets3D.fits`), reported with the set: mean dip / dip
        direction, κ, α95, variability cones, the angle δ between the line and the mean pole, and
        the mean spacing normal to the mean plane (mean spacing along the line × cos δ).
    terzaghi_cap_deg : float, default 15.0
        Blind-zone angle γ of the Terzaghi weights (0 < γ < 90): the largest weight is 1 / sin γ.
    rqd_threshold_m : float, default 0.1
        RQD piece threshold, metres.

    Returns
    -------
    dict
        ``{"scanline": {...}, "all": {...}, "sets": [{...}, ...], "intersections": {...},
        "warnings": [...]}``, JSON-ready
        (undefined values are None). Each group has ``n_intersections``, ``p10_per_m``,
        ``p10_terzaghi_per_m``, ``n_terzaghi_capped``, ``spacing_m`` (the fit, see
        :class:`SpacingFit`), ``spacings_m`` (the spacings it was fitted to, in order along the
        line), ``rqd_priest_hudson_percent``, ``rqd_direct_percent`` and ``trace_length_m``.
        Spacings of a set are measured between that set's hits only. ``"intersections"`` holds the
        survey's hits (``distance_m``, ``dip_deg``, ``dip_direction_deg``, one entry per hit), so a
        report draws the poles and their density from the summary alone.

    Notes
    -----
    A warning is added for each set whose mean plane is within γ of the line (the line is nearly
    parallel to the set: few hits, and capped weights that bias its P10 low, docs/fractures.md §6; Terzaghi 1965).

    Examples
    --------
    >>> s = Scanline(distance_m=[1.0, 2.0, 3.0], dip_deg=[0, 0, 0], dip_direction_deg=[0, 0, 0],
    ...              trend_deg=0.0, plunge_deg=90.0, length_m=4.0)
    >>> stats = scanline_statistics(s)
    >>> stats["all"]["p10_per_m"], stats["all"]["p10_terzaghi_per_m"], stats["all"]["rqd_direct_percent"]
    (0.75, 0.75, 100.0)
    """
    if not isinstance(scanline, Scanline):
        raise TypeError(f"scanline must be a Scanline, got {type(scanline).__name__}")
    cap = _as_scalar(terzaghi_cap_deg, "terzaghi_cap_deg", low=0.0, low_open=True, high=90.0,
                     what="Terzaghi blind-zone angle in degrees, 0 < cap < 90")
    if cap >= 90.0:
        raise ValueError("terzaghi_cap_deg must be < 90 (Terzaghi blind-zone angle in degrees), got 90")
    threshold = _as_scalar(rqd_threshold_m, "rqd_threshold_m", low=0.0, low_open=True,
                           what="RQD piece length in metres")
    n = scanline.n_intersections
    if membership is None:
        labels = np.zeros(n, dtype=np.int64)
    else:
        labels = np.asarray(membership)
        if labels.shape != (n,) or labels.dtype.kind not in "iu":
            raise ValueError(f"membership must be {n} integers (one set index per intersection), "
                             f"got shape {labels.shape} and dtype {labels.dtype}")
        if (labels < -1).any():
            raise ValueError("membership must hold set indices >= 0, or -1 for no set")
    k = int(labels.max()) + 1 if labels.size and labels.max() >= 0 else 0
    fits = list(set_fits) if set_fits is not None else [None] * k
    if len(fits) < k:
        raise ValueError(f"set_fits must have one entry per set ({k}), got {len(fits)}")
    poles = scanline.poles()
    direction = scanline.direction
    out: dict[str, Any] = {
        "scanline": {"trend_deg": scanline.trend_deg, "plunge_deg": scanline.plunge_deg,
                     "length_m": scanline.length_m, "n_intersections": n,
                     "start_xyz_m": None if scanline.start_xyz_m is None else scanline.start_xyz_m.tolist(),
                     "terzaghi_cap_deg": cap, "rqd_threshold_m": threshold},
        "all": _group_statistics(scanline, np.ones(n, dtype=bool), poles, cap, threshold),
        "sets": [],
        "intersections": {"distance_m": scanline.distance_m.tolist(), "dip_deg": scanline.dip_deg.tolist(),
                          "dip_direction_deg": scanline.dip_direction_deg.tolist()},
        "warnings": [],
    }
    for j in range(max(k, len(fits))):
        group = _group_statistics(scanline, labels == j, poles, cap, threshold)
        fit = fits[j] if j < len(fits) else None
        orientation: dict[str, Any] = dict.fromkeys(
            ("mean_dip_deg", "mean_dip_direction_deg", "mean_pole_xyz", "kappa", "alpha95_deg",
             "variability_63_deg", "variability_95_deg", "angle_line_to_pole_deg", "mean_normal_spacing_m"))
        if fit is not None:
            dip, dip_direction = dip_from_normal(fit.mean_pole)
            angle = float(angle_between(fit.mean_pole, direction))  # axial, 0-90
            orientation.update(
                mean_dip_deg=float(dip), mean_dip_direction_deg=float(dip_direction),
                mean_pole_xyz=fit.mean_pole.tolist(), kappa=_finite_or_none(fit.kappa),
                alpha95_deg=_finite_or_none(fit.alpha95_deg),
                variability_63_deg=_finite_or_none(fit.variability_63_deg),
                variability_95_deg=_finite_or_none(fit.variability_95_deg),
                angle_line_to_pole_deg=angle)
            if group["spacing_m"]["mean_m"] is not None:  # apparent spacing x |cos| ([Pri93]_)
                orientation["mean_normal_spacing_m"] = group["spacing_m"]["mean_m"] * math.cos(math.radians(angle))
            if angle > 90.0 - cap:
                out["warnings"].append(
                    f"set {j}: the scanline is {90.0 - angle:.1f}° from the set's mean plane (less than "
                    f"the Terzaghi cap {cap:g}°): few hits, and its P10 is biased low")
        out["sets"].append({"set": j, **orientation, **group})
    return out
