"""Fit of the box-counting dimension: the slope of log N(delta) against log(1/delta).

The error model is reported in three parts, because no single number is honest on its own:

- the ordinary least-squares standard error of the slope and its 95 % interval (Student t with
  n - 2 degrees of freedom). Counts at nested box sizes are not independent, so this is a *lower
  bound* on the uncertainty;
- the local slopes between consecutive sizes, so a crossover (two regimes) is visible rather than
  averaged into one number (docs/fractal.md §4, eq. (4.4));
- the spread of D over shifted box grids (see :mod:`rockmass.fractal.boxcount`), which measures the
  discretisation error of the count itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LineFit", "fit_loglog", "loglog_slopes", "local_slopes", "fit_range_mask"]


@dataclass(frozen=True)
class LineFit:
    """Least-squares line ``log N = intercept + dimension * log(1/delta)``.

    Attributes
    ----------
    dimension : float
        The slope D.
    intercept : float
        log N at delta = 1 (in the units the sizes were given in).
    r2 : float
        Coefficient of determination; 1.0 when the counts are exactly on a line (including the
        degenerate case of constant counts, where the total variance is zero).
    stderr : float
        Standard error of the slope, s / sqrt(Sxx); 0.0 for an exact fit.
    ci95 : tuple of float
        95 % confidence interval of the slope, D -/+ t(0.975, n-2) * stderr.
    n_points : int
        Number of sizes in the fit.
    """

    dimension: float
    intercept: float
    r2: float
    stderr: float
    ci95: tuple[float, float]
    n_points: int


def fit_loglog(sizes, counts) -> LineFit:
    """Fit D by ordinary least squares on ``(log(1/size), log count)``.

    Parameters
    ----------
    sizes : (n,) array of float
        Box sizes, any unit, all > 0 and distinct; n >= 3.
    counts : (n,) array of float
        Occupied boxes at each size, all > 0.

    Returns
    -------
    LineFit

    Raises
    ------
    ValueError
        Fewer than 3 sizes, repeated sizes, or non-positive sizes or counts.

    Notes
    -----
    With x = log(1/delta), y = log N: D = Sxy / Sxx, s^2 = SSres / (n - 2), SE(D) = s / sqrt(Sxx),
    R^2 = 1 - SSres / SStot (docs/fractal.md §4, eqs. (4.1)-(4.3)); D itself is defined by Jiang
    et al.'s eq. 3 (docs/fractal.md §1, eq. (1.1)).

    Examples
    --------
    >>> fit = fit_loglog([1, 2, 4, 8], [64, 32, 16, 8])
    >>> round(fit.dimension, 12), fit.r2
    (1.0, 1.0)
    """
    from scipy.special import stdtrit

    s = np.asarray(sizes, dtype=np.float64)
    c = np.asarray(counts, dtype=np.float64)
    if s.shape != c.shape or s.ndim != 1:
        raise ValueError(f"sizes and counts must be 1-D of equal length, got {s.shape} and {c.shape}")
    if s.size < 3:
        raise ValueError(f"a dimension fit needs at least 3 box sizes, got {s.size}")
    if not (np.all(s > 0) and np.all(c > 0)):
        raise ValueError("box sizes and counts must all be > 0 (an empty box count has no dimension)")
    if np.unique(s).size != s.size:
        raise ValueError("box sizes must be distinct")
    x, xm, sxx = _centred_x(s)
    y = np.log(c)
    ym = y.mean()
    slope = np.sum((x - xm) * (y - ym)) / sxx
    intercept = ym - slope * xm
    resid = y - (intercept + slope * x)
    ss_res = float(np.sum(resid**2))
    ss_tot = float(np.sum((y - ym) ** 2))
    dof = s.size - 2
    # exact fits leave round-off residuals; treat them as zero relative to the data's own scale
    if ss_res <= 1e-24 * max(ss_tot, 1.0) * s.size:
        ss_res = 0.0
    r2 = 1.0 if ss_tot == 0.0 else max(0.0, 1.0 - ss_res / ss_tot)
    stderr = float(np.sqrt(ss_res / dof / sxx))
    half = float(stdtrit(dof, 0.975)) * stderr
    return LineFit(float(slope), float(intercept), float(r2), stderr,
                   (float(slope - half), float(slope + half)), int(s.size))


def _centred_x(sizes: np.ndarray):
    """x = log(1/size), its mean and Sxx: the one place both fits compute them."""
    x = -np.log(sizes)
    xm = x.mean()
    return x, xm, np.sum((x - xm) ** 2)


def loglog_slopes(sizes, counts) -> np.ndarray:
    """The slope D of :func:`fit_loglog` for each column of ``counts``, ``(k,) float64``.

    sizes : (n,) float64, all > 0 and distinct; counts : (n, k), all > 0 (not checked: the caller
    has validated them). Each slope is computed with the same operations on one contiguous row as
    :func:`fit_loglog`, so it is bit for bit the slope that function returns; only the statistics
    (R^2, standard error, interval) are left out, which is what makes it cheap for many columns.

    Examples
    --------
    >>> loglog_slopes([1, 2, 4], [[16, 16], [8, 4], [4, 1]]).round(12).tolist()
    [1.0, 2.0]
    """
    x, xm, sxx = _centred_x(np.asarray(sizes, dtype=np.float64))
    y = np.log(np.ascontiguousarray(np.asarray(counts, dtype=np.float64).T))  # (k, n) rows
    ym = y.mean(axis=1)
    return np.sum((x - xm) * (y - ym[:, None]), axis=1) / sxx


def local_slopes(sizes, counts) -> np.ndarray:
    """Slopes between consecutive sizes, -d log N / d log delta, ``(n - 1,) float64``.

    Sizes must be sorted ascending. A constant local slope means a power law over that range; a
    drift or a step shows a crossover.

    Examples
    --------
    >>> local_slopes([1, 2, 4], [16, 8, 2]).round(12).tolist()
    [1.0, 2.0]
    """
    s = np.log(np.asarray(sizes, dtype=np.float64))
    c = np.log(np.asarray(counts, dtype=np.float64))
    return -np.diff(c) / np.diff(s)


def fit_range_mask(sizes_px, fit_range_px, grid: int) -> np.ndarray:
    """Which sizes fall in the fit range ``[min, max]`` (inclusive, grid pixels).

    ``fit_range_px=None`` is the default range: from the smallest size up to a quarter of the side
    (docs/fractal.md §4: larger boxes are too few to count). Raises ``ValueError`` naming the range when
    fewer than 3 sizes fall in it.
    """
    sizes_px = np.asarray(sizes_px, dtype=np.float64)
    if fit_range_px is None:
        lo, hi = float(sizes_px.min()), grid / 4.0
        what = f"the default fit range [smallest size, grid/4] = [{lo:g}, {hi:g}] px"
    else:
        values = np.asarray(fit_range_px, dtype=np.float64).ravel()
        if values.size != 2:
            raise ValueError(f"fit range must be (min, max) box sizes in pixels, got {fit_range_px!r}")
        lo, hi = float(values[0]), float(values[1])
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
            raise ValueError(f"fit range must be (min, max) box sizes in pixels with 0 < min < max, "
                             f"got {tuple(fit_range_px)}")
        what = f"the fit range [{lo:g}, {hi:g}] px"
    tol = 1e-9 * hi
    inside = (sizes_px >= lo - tol) & (sizes_px <= hi + tol)
    if inside.sum() < 3:
        raise ValueError(
            f"grid {grid} has only {int(inside.sum())} box sizes in {what}; a fit needs at least 3 "
            f"(available sizes: {sizes_px.tolist()}). Use a larger grid or a wider range.")
    return inside
