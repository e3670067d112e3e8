"""Lower-hemisphere equal-area (Schmidt) stereonets of poles, with set means, cones and great circles.

Projection (Lambert azimuthal equal-area, lower hemisphere, primitive circle of radius 1, North up,
East right): a unit vector v = (x, y, z) with z <= 0 plots at

    (X, Y) = (x, y) / sqrt(1 - z)

so r = sqrt(1 + z) = √2 sin(θ/2), θ the angle from straight down: the vertical plots at the centre
and horizontal lines on the primitive. Vectors with z > 0 are flipped first (axial data). Equal areas
on the sphere stay equal on the net, so point densities can be compared by eye.

matplotlib is imported inside :func:`plot_stereonet` (Agg backend); this module loads only numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .fisher import _orthonormal_basis
from .orientation import _as_vectors, to_lower_hemisphere

__all__ = ["equal_area_xy", "plot_stereonet", "small_circle"]


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
