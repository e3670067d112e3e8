"""Figures of trace maps: the length-weighted, equal-area, axial rose diagram and the map by set.

matplotlib is imported inside each function (Agg backend), so importing :mod:`rockmass.dfn` stays
light. Each function writes a file whose format follows its suffix.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rose_petals", "rose_diagram", "plot_trace_map"]


def _figure(size):
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


def _segment_colours(trace_map, set_ids, unassigned: str) -> list[str]:
    """One matplotlib colour per straight segment of ``trace_map``: its set's cycle colour ``C<set>``,
    the grey ``unassigned`` for set -1, all ``C0`` when ``set_ids`` is None."""
    owner = trace_map.segment_trace_index()
    if set_ids is None:
        return ["C0"] * owner.size
    per_segment = np.asarray(set_ids)[owner]
    return [unassigned if s < 0 else f"C{int(s) % 10}" for s in per_segment]


def _set_legend(ax, set_ids) -> None:
    """A legend entry per assigned set, in the colours of :func:`_segment_colours` (none without sets)."""
    if set_ids is None:
        return
    for s in sorted(set(int(v) for v in np.asarray(set_ids) if v >= 0)):
        ax.plot([], [], color=f"C{s % 10}", label=f"set {s}")
    ax.legend(fontsize=8, loc="upper right")


def rose_petals(angles_deg, weights, bin_deg: float = 10.0):
    """Bin edges (deg, 0–360) and equal-area petal radii of axial angles.

    Each angle θ (0–180°, axial) adds its weight to the bin of θ and of θ + 180°. The radius of a
    petal is the square root of its weight share, so petal *area* is proportional to the length of
    traces in the bin (an equal-area rose; a radius proportional to the weight would exaggerate the
    dominant set by the square of its share).

    Examples
    --------
    >>> edges, radii = rose_petals([10.0, 10.0, 100.0], [1.0, 1.0, 2.0], bin_deg=90.0)
    >>> edges.tolist(), radii.round(6).tolist()
    ([0.0, 90.0, 180.0, 270.0, 360.0], [0.707107, 0.707107, 0.707107, 0.707107])
    """
    a = np.mod(np.asarray(angles_deg, dtype=np.float64), 180.0)
    w = np.asarray(weights, dtype=np.float64)
    if a.shape != w.shape:
        raise ValueError(f"angles_deg and weights must have the same shape, got {a.shape} and {w.shape}")
    if not (0 < bin_deg <= 90 and (180.0 / bin_deg).is_integer()):
        raise ValueError(f"bin_deg must divide 180 and be in (0, 90], got {bin_deg}")
    ok = np.isfinite(a) & np.isfinite(w) & (w > 0)
    n_half = int(round(180.0 / bin_deg))
    half, _ = np.histogram(a[ok], bins=n_half, range=(0.0, 180.0), weights=w[ok])
    total = half.sum()
    share = half / total if total > 0 else half
    radii = np.sqrt(np.concatenate([share, share]))
    edges = np.linspace(0.0, 360.0, 2 * n_half + 1)
    return edges, radii


def rose_diagram(angles_deg, weights, path, *, bin_deg: float = 10.0, set_means_deg=None,
                 title: str | None = None, convention: str = "face") -> None:
    """Write an equal-area, axial, length-weighted rose diagram of trace angles.

    Parameters
    ----------
    angles_deg : (n,) array_like
        Trace angles, 0–180 (axial), in ``convention``.
    weights : (n,) array_like
        Trace lengths (or any non-negative weights); NaN angles and zero weights are skipped.
    path : path-like
        Output file (PNG, SVG, PDF by suffix).
    bin_deg : float, default 10
        Bin width; must divide 180.
    set_means_deg : array_like, optional
        Mean angles of the joint sets, drawn as lines through the centre.
    title : str, optional
    convention : {"face", "azimuth"}, default "face"
        ``"face"``: counter-clockwise from +u (the face's right), 0° drawn to the right;
        ``"azimuth"``: clockwise from North, 0° drawn up and angles growing clockwise, as a map
        user reads a rose (:mod:`rockmass.dfn.frames`). The figure says which.
    """
    from .frames import ANGLE_CONVENTIONS

    if convention not in ANGLE_CONVENTIONS:
        raise ValueError(f"convention must be one of {', '.join(map(repr, ANGLE_CONVENTIONS))}, got {convention!r}")
    edges, radii = rose_petals(angles_deg, weights, bin_deg)
    fig = _figure((5.0, 5.2))
    ax = fig.add_subplot(projection="polar")
    width = np.radians(np.diff(edges))
    ax.bar(np.radians(edges[:-1]), radii, width=width, align="edge", color="C0", alpha=0.75,
           edgecolor="white", linewidth=0.5)
    top = float(radii.max()) if radii.size and radii.max() > 0 else 1.0
    means = [] if set_means_deg is None else np.atleast_1d(set_means_deg)
    for k, mean in enumerate(means):  # a diameter through the centre at the set's mean angle
        t = np.radians(mean)
        ax.plot([t, t, t + np.pi], [top, 0.0, top], color=f"C{k % 10}", lw=1.5,
                label=f"set {k}: {mean:03.0f}°" if convention == "azimuth" else f"set {k}: {mean:.0f}°")
    if len(means):
        ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(-0.1, -0.12))
    if convention == "azimuth":
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
    else:
        ax.set_theta_zero_location("E")
        ax.set_theta_direction(1)
    ax.set_yticklabels([])
    ax.set_title(title or "trace orientations (length-weighted, equal-area, axial)", fontsize=9)
    ax.set_xlabel("azimuth, clockwise from North" if convention == "azimuth"
                  else "angle, counter-clockwise from +u (face frame)", fontsize=8)
    fig.savefig(path, dpi=120)


def plot_trace_map(trace_map, path, *, set_ids=None, title: str | None = None,
                   unit: str = "m") -> None:
    """Write a map of the traces coloured by set (grey for unassigned), with the window outline."""
    from matplotlib.collections import LineCollection

    fig = _figure((8.0, 6.0))
    ax = fig.add_subplot()
    seg = trace_map.segments()
    lines = seg.reshape(-1, 2, 2)
    ax.add_collection(LineCollection(lines, colors=_segment_colours(trace_map, set_ids, "0.6"), linewidths=1.0))
    if trace_map.window_xy_m is not None:
        ring = np.vstack([trace_map.window_xy_m, trace_map.window_xy_m[:1]])
        ax.plot(ring[:, 0], ring[:, 1], color="k", lw=1.0)
    _set_legend(ax, set_ids)
    ax.autoscale()
    ax.set_aspect("equal")
    is_map = trace_map.frame == "map"
    ax.set_xlabel(f"{'easting x' if is_map else 'u'} ({unit})")
    ax.set_ylabel(f"{'northing y' if is_map else 'v'} ({unit})")
    ax.set_title(title or "traces by set", fontsize=10)
    fig.savefig(path, dpi=120)
