"""Figures of trace maps and scanlines.

Written to a file (format by suffix): the length-weighted, equal-area, axial rose diagram and the
trace map by set. Returned as a matplotlib :class:`~matplotlib.figure.Figure` for a report (each
drawn only from numbers that a stage summary holds): the XYI ternary diagram of the node counts
(:func:`plot_xyi_ternary`), the trace-length distribution (:func:`plot_trace_lengths`), the P21 map
(:func:`plot_p21_map`), the spacing histograms of a scanline (:func:`plot_spacings`) and its RQD
(:func:`plot_rqd`).

matplotlib is imported inside each function (Agg backend, no pyplot state), so importing
:mod:`rockmass.dfn` stays light.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rose_petals", "rose_diagram", "plot_trace_map", "ternary_xy", "connections_per_branch_line",
           "plot_xyi_ternary", "plot_trace_lengths", "plot_p21_map", "plot_spacings", "plot_rqd"]


def _figure(size, layout: str | None = "constrained"):
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout=layout)


def _segment_colours(trace_map, set_ids, unassigned: str) -> np.ndarray:
    """(n_segments, 4) RGBA colours of the straight segments of ``trace_map``: its set's cycle
    colour ``C<set>``, the grey ``unassigned`` for set -1, all ``C0`` when ``set_ids`` is None.
    Each set's colour name is converted once, not once per segment."""
    from matplotlib.colors import to_rgba

    owner = trace_map.segment_trace_index()
    per_segment = np.zeros(owner.size, np.int64) if set_ids is None else np.asarray(set_ids)[owner]
    sets, index = np.unique(per_segment, return_inverse=True)
    palette = np.array([to_rgba(unassigned if s < 0 else f"C{int(s) % 10}") for s in sets])
    return palette.reshape(-1, 4)[index.reshape(-1)]


def _set_legend(ax, set_ids, **placement) -> None:
    """A legend entry per assigned set, in the colours of :func:`_segment_colours` (none without
    sets); ``placement``: matplotlib's legend placement (default: the axes' upper right)."""
    if set_ids is None:
        return
    for s in sorted(set(int(v) for v in np.asarray(set_ids) if v >= 0)):
        ax.plot([], [], color=f"C{s % 10}", label=f"set {s}")
    ax.legend(fontsize=8, **({"loc": "upper right"} | placement))


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
    # the default margins hold the title, labels and legend of one polar axes: no layout solver,
    # which ``rockmass extract`` would run on every photo for nothing
    fig = _figure((5.0, 5.2), layout=None)
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


# -------------------------------------------------------------------------- topology: XYI ternary --

#: Corners of the XYI triangle (side 1): I at the top, Y bottom left, X bottom right.
_CORNERS = {"I": (0.5, np.sqrt(3.0) / 2.0), "Y": (0.0, 0.0), "X": (1.0, 0.0)}
#: Connections per branch C_B of the reference lines of :func:`plot_xyi_ternary`.
CB_LINES = (1.0, 1.2, 1.4, 1.6, 1.8)


def ternary_xy(n_i, n_y, n_x) -> np.ndarray:
    """Cartesian position in the XYI triangle of node counts (barycentric coordinates).

    With proportions p_I, p_Y, p_X (the counts over N_I + N_Y + N_X; E nodes are not part of the
    diagram), the point is p_I·I + p_Y·Y + p_X·X with the corners I = (1/2, √3/2), Y = (0, 0),
    X = (1, 0) (:data:`_CORNERS`), so x = p_X + p_I/2 and y = (√3/2) p_I.

    Parameters
    ----------
    n_i, n_y, n_x : float or array_like
        Node counts, >= 0, not all zero.

    Returns
    -------
    (..., 2) ndarray of float64

    Examples
    --------
    >>> ternary_xy(2, 1, 1).round(6).tolist()      # p = (1/2, 1/4, 1/4)
    [0.5, 0.433013]
    """
    counts = np.stack(np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (n_i, n_y, n_x))), -1)
    total = counts.sum(axis=-1, keepdims=True)
    if np.any(counts < 0) or np.any(total <= 0):
        raise ValueError(f"node counts must be >= 0 and not all zero, got I, Y, X = {counts.tolist()}")
    p = counts / total
    corners = np.array([_CORNERS["I"], _CORNERS["Y"], _CORNERS["X"]])
    return p @ corners


def connections_per_branch_line(c_b: float) -> np.ndarray:
    """End points ``(2, 2)`` of the line of constant connections per branch in the XYI triangle.

    With C_B = (3 N_Y + 4 N_X) / N_B and N_B = (N_I + 3 N_Y + 4 N_X) / 2 (docs/fractures.md §9,
    Sanderson & Nixon 2015), C_B = c is linear in the proportions: it meets the I-Y side at
    p_Y = c / (6 − 2c) and the I-X side at p_X = c / (8 − 3c); 0 <= c < 2 (c = 0 is the I corner,
    c → 2 the Y-X side).

    Examples
    --------
    >>> connections_per_branch_line(1.0).round(4).tolist()   # p_Y = 1/4 on I-Y, p_X = 1/5 on I-X
    [[0.375, 0.6495], [0.6, 0.6928]]
    """
    c = float(c_b)
    if not 0.0 <= c < 2.0:
        raise ValueError(f"c_b must be in [0, 2) (connections per branch), got {c_b}")
    p_y, p_x = c / (6.0 - 2.0 * c), c / (8.0 - 3.0 * c)
    return np.vstack([ternary_xy(1.0 - p_y, p_y, 0.0), ternary_xy(1.0 - p_x, 0.0, p_x)])


def plot_xyi_ternary(n_i: int, n_y: int, n_x: int, *, title: str | None = None):
    """The XYI ternary diagram of a network's node counts (Sanderson & Nixon 2015), as a Figure.

    The triangle has I at the top, Y bottom left and X bottom right (:func:`ternary_xy`), a grid
    every 20 %, and grey reference lines of constant connections per branch C_B
    (:data:`CB_LINES`, :func:`connections_per_branch_line`): isolated networks sit near I, well
    connected ones near the Y-X side. The network is one black dot, labelled with its counts
    (docs/fractures.md §9).

    References
    ----------
    .. [SN15] Sanderson, D. J., Nixon, C. W. (2015). The use of topology in fracture network
       characterization. Journal of Structural Geology 72, 55-66. doi:10.1016/j.jsg.2015.01.005
    """
    fig = _figure((5.0, 4.6))
    ax = fig.add_subplot()
    tri = np.array([_CORNERS["I"], _CORNERS["Y"], _CORNERS["X"], _CORNERS["I"]])
    ax.plot(tri[:, 0], tri[:, 1], color="black", lw=1.0)
    for f in (0.2, 0.4, 0.6, 0.8):  # proportion f of each node kind
        for a, b in (((f, 1 - f, 0), (f, 0, 1 - f)), ((1 - f, f, 0), (0, f, 1 - f)), ((1 - f, 0, f), (0, 1 - f, f))):
            ax.plot(*np.vstack([ternary_xy(*a), ternary_xy(*b)]).T, color="0.85", lw=0.5)
    for k, c in enumerate(CB_LINES):
        ends = connections_per_branch_line(c)
        ax.plot(*ends.T, color="0.5", lw=0.8, ls="--", label=None if k else "constant connections per branch C_B")
        ax.text(*ends[1], f" {c:.1f}", fontsize=7, color="0.4", va="center")
    for name, (x, y) in _CORNERS.items():
        ax.text(x, y + (0.04 if name == "I" else -0.06), name, ha="center", fontsize=12)
    xy = ternary_xy(n_i, n_y, n_x)
    ax.scatter([xy[0]], [xy[1]], s=50, color="black", zorder=5, label=f"I {n_i}, Y {n_y}, X {n_x}")
    ax.legend(loc="upper left", fontsize=7, frameon=False)
    ax.set_xlim(-0.08, 1.08)
    ax.set_ylim(-0.1, 0.95)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title or "XYI node proportions", fontsize=10)
    return fig


# -------------------------------------------------------------------------- trace lengths, P21 map --


def plot_trace_lengths(lengths, censored, *, fitted_survival=None, fitted_label: str = "fitted law",
                       unit: str = "m", title: str | None = None):
    """Complementary cumulative distribution of trace lengths on log-log axes, as a Figure.

    Parameters
    ----------
    lengths : (n,) array_like
        Trace lengths inside the window (the summary's clipped lengths); zero and non-finite lengths
        are left out.
    censored : (n,) array_like of bool
        True for a trace with an end on the window edge: its length is a lower bound, drawn as an
        open marker; complete traces are filled.
    fitted_survival : callable, optional
        ``S(l)``: the fraction of trace lengths >= l under a fitted law, drawn as a line over the
        observed range.
    fitted_label : str
        Legend text of that line.

    Notes
    -----
    The empirical CCDF at the k-th longest of n lengths is k / n (the fraction at least that long).
    """
    length = np.asarray(lengths, dtype=np.float64).reshape(-1)
    cut = np.asarray(censored, dtype=bool).reshape(-1)
    if cut.shape != length.shape:
        raise ValueError(f"censored must have one entry per length ({length.size}), got {cut.size}")
    keep = np.isfinite(length) & (length > 0)
    length, cut = length[keep], cut[keep]
    order = np.argsort(-length, kind="stable")
    length, cut = length[order], cut[order]
    ccdf = np.arange(1, length.size + 1) / max(length.size, 1)
    fig = _figure((5.6, 4.4))
    ax = fig.add_subplot()
    ax.scatter(length[~cut], ccdf[~cut], s=14, color="C0", label=f"complete ({int((~cut).sum())})")
    ax.scatter(length[cut], ccdf[cut], s=14, facecolors="none", edgecolors="C1",
               label=f"censored by the window ({int(cut.sum())}): lower bounds")
    if fitted_survival is not None and length.size:
        grid = np.geomspace(length.min(), length.max(), 200)
        ax.plot(grid, fitted_survival(grid), color="k", lw=1.2, label=fitted_label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"trace length l ({unit})")
    ax.set_ylabel("fraction of traces at least l long")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="lower left")
    ax.set_title(title or "trace-length distribution (complementary cumulative)", fontsize=10)
    return fig


def plot_p21_map(p21, origin_xy, cell_size: float, *, window_xy=None, unit: str = "m",
                 title: str | None = None):
    """P21 per cell as a colour map (cells outside the window blank), with the window outline.

    Parameters
    ----------
    p21 : (ny, nx) array_like
        P21 of each cell, row 0 at the bottom; NaN or None for a cell outside the window.
    origin_xy : (2,) array_like
        Lower-left corner of cell (0, 0).
    cell_size : float
        Side of a cell.
    window_xy : (k, 2) array_like, optional
        The window's outline.
    """
    values = np.array([[np.nan if v is None else v for v in row] for row in p21], dtype=np.float64)
    ny, nx = values.shape
    x0, y0 = (float(v) for v in origin_xy)
    fig = _figure((6.4, 5.0))
    ax = fig.add_subplot()
    mesh = ax.pcolormesh(x0 + cell_size * np.arange(nx + 1), y0 + cell_size * np.arange(ny + 1),
                         np.ma.masked_invalid(values), cmap="viridis", shading="flat")
    fig.colorbar(mesh, ax=ax, shrink=0.85, label=f"P21 ({unit}/{unit}²)")
    if window_xy is not None:
        ring = np.asarray(window_xy, dtype=np.float64)
        ring = np.vstack([ring, ring[:1]])
        ax.plot(ring[:, 0], ring[:, 1], color="k", lw=1.0)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_title(title or f"P21 on {cell_size:.3g} {unit} cells", fontsize=10)
    return fig


# ------------------------------------------------------------------------------- scanline: spacings --


def plot_spacings(groups, *, title: str | None = None):
    """Histograms of scanline spacings with the fitted exponential and lognormal densities.

    Parameters
    ----------
    groups : sequence of (label, spacings_m, fit)
        One panel each: the label (``"all"``, ``"set 0"``, ...), the spacings (m) and the fit as
        the summary holds it (:meth:`rockmass.dfn.scanline_stats.SpacingFit.as_dict`): the
        exponential density λ e^(−λs) from ``fit["exponential"]["rate_per_m"]`` and the lognormal
        density from ``fit["lognormal"]["mu_log_m"]`` and ``["sigma_log"]``, each drawn when
        defined, the preferred one (``fit["preferred"]``) solid. A group with no spacing gets a
        panel that says so.
    """
    groups = list(groups)
    fig = _figure((4.2 * max(len(groups), 1), 3.6))
    axes = fig.subplots(1, max(len(groups), 1), squeeze=False)[0]
    for ax, (label, spacings, fit) in zip(axes, groups):
        s = np.asarray(spacings, dtype=np.float64).reshape(-1)
        s = s[np.isfinite(s)]
        ax.set_title(f"{label}: {s.size} spacings", fontsize=9)
        ax.set_xlabel("spacing along the line (m)")
        if not s.size:
            ax.text(0.5, 0.5, "no spacing (fewer than 2 hits)", ha="center", transform=ax.transAxes)
            continue
        ax.hist(s, bins=max(5, min(30, int(np.sqrt(s.size)) + 2)), density=True, color="0.8",
                edgecolor="white")
        grid = np.linspace(max(s.min(), 1e-9) * 0.5, s.max() * 1.05, 300)
        fit = fit or {}
        for key, colour in (("exponential", "C0"), ("lognormal", "C3")):
            pdf, text = _spacing_pdf(key, fit.get(key) or {}, grid)
            if pdf is not None:
                ax.plot(grid, pdf, color=colour, lw=1.5, ls="-" if fit.get("preferred") == key else "--",
                        label=text + (" (preferred)" if fit.get("preferred") == key else ""))
        ax.legend(fontsize=7)
    axes[0].set_ylabel("probability density (1/m)")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def _spacing_pdf(key: str, law: dict, s: np.ndarray):
    """(density at s or None, legend text) of one fitted spacing law of the summary."""
    if key == "exponential" and law.get("rate_per_m"):
        lam = float(law["rate_per_m"])
        return lam * np.exp(-lam * s), f"exponential, mean {1 / lam:.3g} m{_ks_text(law)}"
    if key == "lognormal" and law.get("mu_log_m") is not None and law.get("sigma_log"):
        mu, sigma = float(law["mu_log_m"]), float(law["sigma_log"])
        pdf = np.exp(-0.5 * ((np.log(s) - mu) / sigma) ** 2) / (s * sigma * np.sqrt(2 * np.pi))
        return pdf, f"lognormal, median {np.exp(mu):.3g} m{_ks_text(law)}"
    return None, ""


def _ks_text(law: dict) -> str:
    p = law.get("ks_p_value")
    return "" if p is None else f", KS p {p:.2f}"


def plot_rqd(labels, rqd_direct, rqd_priest_hudson, *, threshold_m: float = 0.1, title: str | None = None):
    """RQD per group of a scanline as bars: measured on the line and Priest & Hudson's expectation.

    Parameters
    ----------
    labels : sequence of str
        The groups (``"all"``, ``"set 0"``, ...).
    rqd_direct, rqd_priest_hudson : sequence of float or None
        RQD (%) measured on the line and 100 e^(−λt)(λt + 1) from its P10 λ (Priest & Hudson 1976),
        as the summary holds them; None leaves the bar out.
    """
    labels = list(labels)
    x = np.arange(len(labels))
    fig = _figure((1.2 * max(len(labels), 2) + 2.0, 3.4))
    ax = fig.add_subplot()
    for k, (values, name) in enumerate(((rqd_direct, "measured on the line"),
                                        (rqd_priest_hudson, "Priest & Hudson, from P10"))):
        v = np.array([np.nan if r is None else r for r in values], dtype=np.float64)
        bars = ax.bar(x + (k - 0.5) * 0.38, np.nan_to_num(v), width=0.36, color=f"C{k}", label=name)
        for bar, value in zip(bars, v):
            if np.isfinite(value):
                ax.text(bar.get_x() + bar.get_width() / 2, value + 1, f"{value:.0f}", ha="center", fontsize=7)
    ax.set_xticks(x, labels)
    ax.set_ylim(0, 110)
    ax.set_ylabel(f"RQD (%), pieces >= {threshold_m:g} m")
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(title or "RQD along the scanline", fontsize=10)
    return fig
