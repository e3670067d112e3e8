"""Lower-hemisphere equal-area (Schmidt) stereonets of poles, with set means, cones and great circles.

Projection (Lambert azimuthal equal-area, lower hemisphere, primitive circle of radius 1, North up,
East right): a unit vector v = (x, y, z) with z <= 0 plots at

    (X, Y) = (x, y) / sqrt(1 - z)

so r = sqrt(1 + z) = √2 sin(θ/2), θ the angle from straight down: the vertical plots at the centre
and horizontal lines on the primitive. Vectors with z > 0 are flipped first (axial data). Equal areas
on the sphere stay equal on the net, so point densities can be compared by eye.

Pole density (:func:`pole_density`, drawn by :func:`plot_pole_density`) is a sum of axial Fisher
kernels, one per pole, with the concentration of Vollmer's exponential form of Kamb's method
(:func:`kamb_kappa`): contours in multiples of a uniform density (MUD); docs/fractures.md §3.4.

matplotlib is imported inside the plotting functions (Agg backend); this module loads only numpy.

References
----------
.. [Kam59] Kamb, W. B. (1959). Ice petrofabric observations from Blue Glacier, Washington, in relation
   to theory and experiment. Journal of Geophysical Research 64(11), 1891-1909.
.. [Vol95] Vollmer, F. W. (1995). C program for automatic contouring of spherical orientation data
   using a modified Kamb method. Computers & Geosciences 21(1), 31-49.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .fisher import _orthonormal_basis
from .orientation import _as_vectors, to_lower_hemisphere

#: Direction-pole pairs evaluated per pass of :func:`pole_density` (about 32 MB of cosines).
_DENSITY_CHUNK = 4_000_000

__all__ = ["equal_area_xy", "equal_area_vectors", "kamb_kappa", "plot_pole_density", "plot_stereonet",
           "pole_density", "small_circle"]


def equal_area_xy(vectors: ArrayLike) -> np.ndarray:
    """Lower-hemisphere equal-area coordinates of directions, ``(..., 2)`` float64 (X East, Y North).

    Examples
    --------
    >>> equal_area_xy([[0, 0, -1], [1, 0, 0], [0, 0, 1]]) + 0.0
    array([[0., 0.],
           [1., 0.],
           [0., 0.]])
    """
    v = to_lower_hemisphere(_as_vectors(vectors, "vectors"))
    return v[..., :2] / np.sqrt(1.0 - v[..., 2:3])


def small_circle(axis: ArrayLike, half_angle_deg: float, n: int = 181) -> np.ndarray:
    """Equal-area trace of the cone of half-angle α about ``axis``, as ``(m, 2)`` with NaN breaks.

    The cone's points on the upper hemisphere are flipped to the lower one (the same lines), which
    makes the curve jump across the net where it crosses the primitive circle; a NaN row is put at
    each jump so that a plotted line does not draw a chord. α = 90° gives the great circle of the
    plane whose pole is ``axis``.

    Examples
    --------
    >>> xy = small_circle([0, 0, -1], 90.0, n=5)      # the horizontal plane's great circle
    >>> np.allclose(np.hypot(*xy[np.isfinite(xy[:, 0])].T), 1.0)
    True
    """
    centre = to_lower_hemisphere(_as_vectors(axis, "axis"))
    if centre.shape != (3,):
        raise ValueError(f"axis must be one vector of shape (3,), got {centre.shape}")
    alpha = np.radians(float(half_angle_deg))
    e1, e2 = _orthonormal_basis(centre)
    phi = np.linspace(0.0, 2.0 * np.pi, n)
    points = (np.cos(alpha) * centre + np.sin(alpha) * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2))
    upper = points[:, 2] > 0
    xy = equal_area_xy(points)
    jumps = np.flatnonzero(upper[1:] != upper[:-1]) + 1
    return np.insert(xy, jumps, np.nan, axis=0)


def plot_stereonet(poles: ArrayLike, path: Any, *, membership: ArrayLike | None = None,
                   set_fits: Any = None, line_direction: ArrayLike | None = None,
                   title: str | None = None) -> None:
    """Write a lower-hemisphere equal-area stereonet of poles, coloured by set.

    Parameters
    ----------
    poles : (n, 3) array_like
        Poles or normals of the planes (either sign).
    path : path-like
        Output file (PNG, SVG, PDF by suffix).
    membership : (n,) array_like of int, optional
        Set of each pole (-1: none); default all in one colour.
    set_fits : sequence of FisherFit or None, optional
        Per set: the mean pole (square), its confidence cone α95 (solid), variability cone holding
        95 % of the fitted Fisher law (dashed) and the mean plane's great circle (thin).
    line_direction : (3,) array_like, optional
        A scanline's direction, drawn as a triangle.
    title : str, optional
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    unit = _as_vectors(poles, "poles").reshape(-1, 3)
    labels = np.zeros(unit.shape[0], dtype=np.int64) if membership is None else np.asarray(membership)
    if labels.shape != (unit.shape[0],):
        raise ValueError(f"membership must have one entry per pole ({unit.shape[0]}), got shape {labels.shape}")
    fig = Figure(figsize=(5.6, 5.8), layout="constrained")
    ax = fig.add_subplot()
    t = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(np.cos(t), np.sin(t), color="black", linewidth=1.0)
    for angle in range(0, 360, 10):  # ticks every 10°, longer at the cardinal points
        a = np.radians(angle)
        inner = 0.95 if angle % 90 else 0.9
        ax.plot([inner * np.sin(a), np.sin(a)], [inner * np.cos(a), np.cos(a)], color="black", linewidth=0.6)
    ax.plot([-0.03, 0.03], [0, 0], color="grey", linewidth=0.6)
    ax.plot([0, 0], [-0.03, 0.03], color="grey", linewidth=0.6)
    for label, (x, y) in {"N": (0, 1.06), "E": (1.06, 0), "S": (0, -1.1), "W": (-1.1, 0)}.items():
        ax.text(x, y, label, ha="center", va="center", fontsize=10)
    xy = equal_area_xy(unit) if unit.size else np.zeros((0, 2))
    fits = [] if set_fits is None else list(set_fits)
    k = max(int(labels.max()) + 1 if labels.size else 0, len(fits))
    if np.any(labels < 0):
        ax.scatter(*xy[labels < 0].T, s=12, color="lightgrey", label="no set")
    for j in range(max(k, 1)):
        colour = f"C{j % 10}"
        mask = labels == j
        if mask.any():
            ax.scatter(*xy[mask].T, s=14, color=colour, alpha=0.8, edgecolors="none",
                       label=f"set {j} ({int(mask.sum())})")
        fit = fits[j] if j < len(fits) else None
        if fit is None:
            continue
        mean_xy = equal_area_xy(fit.mean_pole)
        ax.scatter(*mean_xy, marker="s", s=45, color=colour, edgecolors="black", zorder=5)
        ax.plot(*small_circle(fit.mean_pole, fit.alpha95_deg).T, color=colour, linewidth=1.4)
        ax.plot(*small_circle(fit.mean_pole, fit.variability_95_deg).T, color=colour, linewidth=1.0,
                linestyle="--")
        ax.plot(*small_circle(fit.mean_pole, 90.0).T, color=colour, linewidth=0.7, alpha=0.7)
    if line_direction is not None:
        ax.scatter(*equal_area_xy(line_direction), marker="^", s=70, color="black", zorder=6, label="scanline")
    ax.set_xlim(-1.15, 1.15)
    ax.set_ylim(-1.15, 1.15)
    ax.set_aspect("equal")
    ax.axis("off")
    if labels.size or line_direction is not None:
        ax.legend(loc="lower left", fontsize=7, frameon=False, bbox_to_anchor=(-0.05, -0.05))
    ax.set_title(title or "Poles, lower hemisphere, equal area", fontsize=10)
    fig.text(0.99, 0.01, "square: mean; solid: α95; dashed: 95 % variability; line: mean plane",
             ha="right", va="bottom", fontsize=6, color="dimgrey")
    fig.savefig(path, dpi=120)


def equal_area_vectors(xy: ArrayLike) -> np.ndarray:
    """Lower-hemisphere unit vectors of net points, the inverse of :func:`equal_area_xy`.

    A point at radius r <= 1 is the direction with z = r² − 1 and horizontal part
    (X, Y) √(2 − r²). Points outside the primitive circle give NaN.

    Examples
    --------
    >>> equal_area_vectors([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]).tolist()
    [[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [nan, nan, nan]]
    """
    p = np.asarray(xy, dtype=np.float64)
    r2 = np.sum(p * p, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore"):
        v = np.concatenate([p * np.sqrt(2.0 - r2), r2 - 1.0], axis=-1)
    return np.where(r2 <= 1.0, v, np.nan)


def kamb_kappa(n_poles: int, sigma: float = 3.0) -> float:
    """Concentration k = 2 (1 + n / σ²) of the smoothing kernel for n poles ([Vol95]_).

    Vollmer's exponential kernel e^(k (cos θ − 1)) with this k stands in for Kamb's counting
    circle ([Kam59]_): the circle whose expected count under a uniform distribution is σ standard
    deviations from zero (σ = 3 by default), so fewer poles give a wider kernel.

    Examples
    --------
    >>> kamb_kappa(9)
    4.0
    """
    if int(n_poles) < 0 or not float(sigma) > 0:
        raise ValueError(f"n_poles must be >= 0 and sigma > 0, got {n_poles} and {sigma}")
    return 2.0 * (1.0 + int(n_poles) / float(sigma) ** 2)


def pole_density(poles: ArrayLike, directions: ArrayLike, *, kappa: float | None = None) -> np.ndarray:
    """Density of poles (per steradian of the lower hemisphere) at ``directions``.

    Parameters
    ----------
    poles : (n, 3) array_like
        Poles (either sign; axial).
    directions : (..., 3) array_like
        Unit vectors where the density is wanted (either sign; NaN rows give NaN).
    kappa : float, optional
        Kernel concentration k > 0; default :func:`kamb_kappa` of n.

    Returns
    -------
    (...,) ndarray of float64
        D(x) = Σ_i [F(x·p_i) + F(−x·p_i)], with the Fisher density on the sphere
        F(c) = k e^(k (c − 1)) / (2π (1 − e^(−2k))) (Fisher 1953). Each pole's pair of kernels
        integrates to 1 over the lower hemisphere, so ∫ D dΩ = n there; a uniform density is
        n / (2π), and D · 2π / n is the density in multiples of it (MUD).

    Examples
    --------
    >>> d = pole_density([[0, 0, 1]], [[0, 0, -1]], kappa=1e-12)   # k -> 0: uniform, 1 / (2π)
    >>> round(float(d[0]) * 2 * np.pi, 9)
    1.0
    """
    p = _as_vectors(poles, "poles").reshape(-1, 3)
    x = np.asarray(directions, dtype=np.float64)
    k = kamb_kappa(p.shape[0]) if kappa is None else float(kappa)
    if not k > 0:
        raise ValueError(f"kappa must be > 0 (kernel concentration), got {kappa}")
    norm = k / (2.0 * np.pi * -np.expm1(-2.0 * k))           # k / (4π sinh k) · e^k, overflow-free
    flat = x.reshape(-1, 3)
    out = np.zeros(flat.shape[0])
    step = max(1, _DENSITY_CHUNK // max(flat.shape[0], 1))   # poles per pass: bounded memory
    for start in range(0, p.shape[0], step):
        c = flat @ p[start:start + step].T                   # (m, chunk) cosines
        out += (np.exp(k * (c - 1.0)) + np.exp(k * (-c - 1.0))).sum(axis=-1)
    return norm * out.reshape(x.shape[:-1])


def plot_pole_density(poles: ArrayLike, *, kappa: float | None = None, n_grid: int = 121,
                      set_means: ArrayLike | None = None, title: str | None = None):
    """Contoured lower-hemisphere equal-area stereonet of pole density in MUD, as a Figure.

    Filled contours of :func:`pole_density` (as multiples of a uniform density) on an
    ``n_grid`` × ``n_grid`` net, the poles as small dots (faint beyond 500 poles), and the set mean
    poles as squares.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    unit = _as_vectors(poles, "poles").reshape(-1, 3)
    n = unit.shape[0]
    if n == 0:
        raise ValueError("poles: no pole to contour (a density needs at least one)")
    k = kamb_kappa(n) if kappa is None else float(kappa)
    g = np.linspace(-1.0, 1.0, int(n_grid))
    xy = np.stack(np.meshgrid(g, g), axis=-1)
    mud = pole_density(unit, equal_area_vectors(xy), kappa=k) * 2.0 * np.pi / n
    fig = Figure(figsize=(5.6, 5.4), layout="constrained")
    ax = fig.add_subplot()
    filled = ax.contourf(g, g, mud, levels=8, cmap="Blues")
    ax.contour(g, g, mud, levels=filled.levels, colors="0.3", linewidths=0.4)
    fig.colorbar(filled, ax=ax, shrink=0.75, label="pole density (multiples of uniform)")
    t = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(np.cos(t), np.sin(t), color="black", linewidth=1.0)
    for label, (x, y) in {"N": (0, 1.06), "E": (1.06, 0), "S": (0, -1.1), "W": (-1.1, 0)}.items():
        ax.text(x, y, label, ha="center", va="center", fontsize=10)
    many = n > 500  # a dense cloud of dots would hide the contours
    ax.scatter(*equal_area_xy(unit).T, s=0.5 if many else 4, color="black", alpha=0.25 if many else 1.0)
    if set_means is not None:
        means = equal_area_xy(np.asarray(set_means, dtype=np.float64).reshape(-1, 3))
        ax.scatter(*means.T, marker="s", s=40, facecolors="none", edgecolors="C3", label="set mean poles")
        ax.legend(loc="lower left", fontsize=7, frameon=False)
    ax.set_xlim(-1.15, 1.15)
    ax.set_ylim(-1.15, 1.15)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title or f"Pole density, {n} poles (lower hemisphere, equal area; Fisher kernel "
                          f"k = {k:.3g}, Kamb σ = 3)", fontsize=9)
    return fig
