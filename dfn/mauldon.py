"""Mauldon's circular-window estimators of trace intensity, density and mean length.

For a circular window of centre c and radius r, let n be the number of points where traces cross the
circle and m the number of trace ends inside it. Mauldon et al. (2001) show that

.. math:: \\hat P_{21} = \\frac{n}{4r}, \\qquad \\hat P_{20} = \\frac{m}{2\\pi r^2}, \\qquad
          \\hat\\mu_L = \\frac{\\pi r}{2}\\,\\frac{n}{m}

are unbiased (the first two) and consistent (the ratio) for a stationary network, whatever the trace
lengths and orientations, because they need neither the lengths of the censored traces nor their
number. This module counts n and m on a trace map (:func:`mauldon_circle`), evaluates the formulas
(:func:`mauldon_from_counts`), and decides whether a window polygon is a circle
(:func:`circle_window`) — fractopo reports the Mauldon values only for circular target areas. On any
other window (a rectangular photograph, a mapped outcrop polygon) :func:`inscribed_circles` places
disjoint circles fully inside it and :func:`mauldon_circles` pools their counts, as Mauldon et al.
(2001) and Rohrbaugh et al. (2002) do with several circles on one map.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .intensity import SamplingWindow, _endpoints_xy, _floor_tolerance, _integer_at_least, _real, _real_at_least
from .tracemap import TraceMap, _as_window, _require_trace_map

__all__ = ["CircleWindow", "MauldonEstimate", "circle_window", "mauldon_circle", "mauldon_from_counts",
           "InscribedCircles", "MauldonCircles", "inscribed_circles", "mauldon_circles"]

#: Default largest radial deviation, relative to the radius, of a polygon still taken for a circle:
#: a regular polygon inscribed in a circle deviates by 1 - cos(pi / k) at its edge midpoints, so 1 %
#: accepts 23 or more vertices (shapely's buffer of a point has 64).
CIRCLE_REL_TOLERANCE = 0.01


@dataclass(frozen=True)
class MauldonEstimate:
    """Mauldon's estimates for one circular window.

    Attributes
    ----------
    centre_xy_m : tuple of float
        Circle centre (x, y) in metres (NaN, NaN when built from counts alone).
    radius_m : float
        Circle radius r in metres.
    n_intersections : int
        n, trace-circle intersections.
    n_endpoints : int
        m, trace ends inside the circle.
    p21_per_m : float
        n / (4r) in m/m².
    p20_per_m2 : float
        m / (2πr²) in 1/m².
    mean_length_m : float
        (πr/2)(n/m) in metres; NaN when m = 0.
    valid : bool
        Whether ``mean_length_m`` is defined (m > 0). P21 and P20 are always defined.
    reason : str
        Why the mean length is not defined ('' when valid).
    """

    centre_xy_m: tuple[float, float]
    radius_m: float
    n_intersections: int
    n_endpoints: int
    p21_per_m: float
    p20_per_m2: float
    mean_length_m: float
    valid: bool
    reason: str


def mauldon_from_counts(n_intersections: int, n_endpoints: int, radius_m: float) -> MauldonEstimate:
    r"""Mauldon's P21, P20 and mean trace length from the counts n and m.

    Parameters
    ----------
    n_intersections : int
        n >= 0, trace-circle intersections (fractopo: E nodes on a circular target area).
    n_endpoints : int
        m >= 0, trace ends inside the circle (fractopo: I + Y nodes).
    radius_m : float
        Circle radius r > 0 in metres.

    Returns
    -------
    MauldonEstimate
        With ``centre_xy_m = (nan, nan)``. When m = 0 the mean length is NaN, ``valid`` is False and
        ``reason`` says why; no division by zero is attempted.

    Notes
    -----
    .. math:: P_{21} = \frac{n}{4r}, \quad P_{20} = \frac{m}{2\pi r^2}, \quad
              \mu_L = \frac{\pi r}{2}\frac{n}{m}

    (Mauldon et al. 2001, eqs. 14, 11 and 13; docs/fractures.md §8, eqs. (8.1)-(8.3)).

    References
    ----------
    .. [1] Mauldon, M., Dunne, W. M., Rohrbaugh, M. B. (2001). Circular scanlines and circular windows:
       new tools for characterizing the geometry of fracture traces. J. Struct. Geol. 23, 247-258.

    Examples
    --------
    >>> e = mauldon_from_counts(40, 10, radius_m=2.0)
    >>> e.p21_per_m, round(e.mean_length_m / math.pi, 12)
    (5.0, 4.0)
    >>> mauldon_from_counts(3, 0, 1.0).reason
    'no trace end inside the circle (m = 0): the mean trace length is undefined'
    """
    n = _integer_at_least(n_intersections, "n_intersections", 0, "a count")
    m = _integer_at_least(n_endpoints, "n_endpoints", 0, "a count")
    r = _real_at_least(radius_m, "radius_m", "circle radius in metres", above_zero=True)
    return _estimate((math.nan, math.nan), r, n, m)


def _estimate(centre: tuple[float, float], r: float, n: int, m: int) -> MauldonEstimate:
    valid = m > 0
    return MauldonEstimate(
        centre_xy_m=centre,
        radius_m=r,
        n_intersections=n,
        n_endpoints=m,
        p21_per_m=n / (4.0 * r),  # Mauldon et al. (2001) eq. 14
        p20_per_m2=m / (2.0 * math.pi * r * r),  # eq. 11
        mean_length_m=0.5 * math.pi * r * n / m if valid else math.nan,  # eq. 13
        valid=valid,
        reason="" if valid else "no trace end inside the circle (m = 0): the mean trace length is undefined",
    )


def mauldon_circle(
    trace_map: TraceMap, centre_xy_m: Any, radius_m: float, *, tolerance_m: float = 0.0
) -> MauldonEstimate:
    """Count n and m for a circle placed on a trace map, and evaluate Mauldon's estimators.

    Parameters
    ----------
    trace_map : TraceMap
        The traces, as digitised (they may run beyond the circle) or clipped to it.
    centre_xy_m : (2,) array_like of float
        Circle centre (x, y) in metres.
    radius_m : float
        Circle radius r > 0 in metres.
    tolerance_m : float, default 0.0
        A trace end within this distance of the circle is on it: it counts as one intersection and
        not as an end inside (so traces clipped to the circle count correctly). >= 0, raised to
        ``1e-9 * 2r`` to absorb rounding.

    Returns
    -------
    MauldonEstimate

    Notes
    -----
    Intersections are counted exactly, segment by segment: the roots t of
    :math:`|p_0 + t (p_1 - p_0) - c|^2 = r^2` in [0, 1) (in [0, 1] for a trace's last segment, so a
    vertex on the circle counts once), in the cancellation-free form :math:`q = -(b + \\mathrm{sign}(b)
    \\sqrt{b^2 - 4ac})/2`, :math:`t = q/a, c/q` (Press et al., Numerical Recipes, §5.6). Tangent
    contacts (a double root) and roots within ``tolerance_m`` of an end on the circle are not counted.

    Examples
    --------
    >>> tm = TraceMap.from_segments([[-2, 0, 2, 0], [0, 0.5, 0, 3]])  # a chord; a trace from inside out
    >>> e = mauldon_circle(tm, (0, 0), 1.0)
    >>> e.n_intersections, e.n_endpoints, e.p21_per_m, e.mean_length_m == math.pi * 3 / 2
    (3, 1, 0.75, True)
    """
    _require_trace_map(trace_map)
    c = np.asarray(centre_xy_m)
    if c.dtype.kind not in "iuf" or c.shape != (2,) or not np.isfinite(c).all():
        raise ValueError(f"centre_xy_m must be one finite point (x, y) in metres, got {c.tolist()!r}")
    c = c.astype(np.float64)
    r = _real_at_least(radius_m, "radius_m", "circle radius in metres", above_zero=True)
    tol = _floor_tolerance(_real_at_least(tolerance_m, "tolerance_m", "snap distance in metres"), 2.0 * r)
    ends = _endpoints_xy(trace_map)  # (n_traces, 2, 2)
    radial = np.hypot(ends[..., 0] - c[0], ends[..., 1] - c[1])
    on_circle = np.abs(radial - r) <= tol
    m = int(np.count_nonzero((radial < r) & ~on_circle))
    n = int(np.count_nonzero(on_circle)) + _crossings(trace_map, c, r, ends, on_circle, tol)
    return _estimate((float(c[0]), float(c[1])), r, n, m)


def _crossings(
    trace_map: TraceMap, c: np.ndarray, r: float, ends: np.ndarray, on_circle: np.ndarray, tol: float
) -> int:
    """Roots of the segment-circle equation, excluding tangencies and points at ends on the circle."""
    seg = trace_map.segments()
    if seg.shape[0] == 0:
        return 0
    owner = trace_map.segment_trace_index()
    p0 = seg[:, :2] - c
    d = seg[:, 2:] - seg[:, :2]
    a = np.einsum("ij,ij->i", d, d)
    b = 2.0 * np.einsum("ij,ij->i", d, p0)
    cc = np.einsum("ij,ij->i", p0, p0) - r * r
    disc = b * b - 4.0 * a * cc
    ok = (a > 0.0) & (disc > 0.0)  # a zero-length piece has no root; a double root is a tangency
    q = np.zeros_like(a)
    q[ok] = -0.5 * (b[ok] + np.copysign(np.sqrt(disc[ok]), b[ok]))
    ok &= q != 0.0
    t = np.full((a.size, 2), -1.0)
    t[ok, 0] = q[ok] / a[ok]
    t[ok, 1] = cc[ok] / q[ok]
    is_last = np.zeros(a.size, dtype=bool)
    is_last[trace_map.offsets[1:] - 2 - np.arange(trace_map.n_traces)] = True  # piece j starts at vertex j + i
    upper = np.where(is_last, 1.0, np.nextafter(1.0, 0.0))[:, None]
    root = (t >= 0.0) & (t <= upper)
    points = seg[:, None, :2] + t[..., None] * d[:, None, :]
    for k in range(2):  # drop roots at (within tol of) a trace end already counted as on the circle
        end = ends[owner, k]
        near = np.hypot(points[..., 0] - end[:, None, 0], points[..., 1] - end[:, None, 1]) <= tol
        root &= ~(near & on_circle[owner, k][:, None])
    return int(np.count_nonzero(root))


@dataclass(frozen=True)
class CircleWindow:
    """Whether a window polygon is a circle, and which.

    Attributes
    ----------
    is_circle : bool
        True when every vertex and every edge midpoint lies within ``rel_tolerance * radius_m`` of the
        fitted circle.
    centre_xy_m : tuple of float
        Centre of the least-squares circle through the vertices, metres.
    radius_m : float
        Its radius in metres.
    max_rel_deviation : float
        Largest radial distance of a vertex or edge midpoint from the circle, divided by the radius.
    reason : str
        Why the polygon is not a circle ('' when it is).
    """

    is_circle: bool
    centre_xy_m: tuple[float, float]
    radius_m: float
    max_rel_deviation: float
    reason: str


def circle_window(window: Any, *, rel_tolerance: float = CIRCLE_REL_TOLERANCE) -> CircleWindow:
    r"""Fit a circle to a window polygon and decide whether the polygon is (approximately) that circle.

    Parameters
    ----------
    window : (k, 2) array_like of float, shapely.Polygon or SamplingWindow
        The window ring (k >= 3), as for :class:`~rockmass.dfn.TraceMap`.
    rel_tolerance : float, default 0.01
        Largest accepted radial deviation relative to the radius, in (0, 1).

    Returns
    -------
    CircleWindow

    Notes
    -----
    The circle is the algebraic least-squares fit of Kåsa (1976): with the vertices centred on their
    mean and scaled by their RMS distance, solve :math:`2 a x + 2 b y + e = x^2 + y^2` for
    (a, b, e); then the centre is (a, b) and :math:`r = \sqrt{e + a^2 + b^2}`. Vertices alone cannot
    tell a circle from an inscribed square, so edge midpoints are tested as well: an inscribed regular
    k-gon deviates by :math:`1 - \cos(\pi/k)` at its midpoints.

    References
    ----------
    .. [1] Kåsa, I. (1976). A circle fitting procedure and its error analysis. IEEE Transactions on
       Instrumentation and Measurement IM-25(1), 8-14.

    Examples
    --------
    >>> import shapely
    >>> disk = shapely.Point(3.0, 4.0).buffer(2.0)  # a 64-gon
    >>> c = circle_window(disk)
    >>> c.is_circle, round(c.centre_xy_m[0], 9), round(c.radius_m, 9)
    (True, 3.0, 2.0)
    >>> circle_window([(0, 0), (1, 0), (1, 1), (0, 1)]).is_circle
    False
    """
    if isinstance(window, SamplingWindow):
        window = window.polygon
    try:
        ring = _as_window(window)
    except ValueError as exc:
        raise ValueError(f"window: {exc}") from exc
    rel = _real(rel_tolerance, "rel_tolerance")
    if not 0.0 < rel < 1.0:
        raise ValueError(f"rel_tolerance must be in (0, 1) (radial deviation / radius), got {rel}")
    mean = ring.mean(axis=0)
    scale = float(np.sqrt(((ring - mean) ** 2).sum(axis=1).mean()))
    xy = (ring - mean) / scale
    design = np.column_stack([2.0 * xy, np.ones(len(xy))])
    (a, b, e), *_ = np.linalg.lstsq(design, (xy**2).sum(axis=1), rcond=None)
    radius = math.sqrt(max(e + a * a + b * b, 0.0)) * scale
    centre = mean + scale * np.array([a, b])
    midpoints = 0.5 * (ring + np.roll(ring, -1, axis=0))
    probe = np.vstack([ring, midpoints])
    deviation = float(np.abs(np.hypot(*(probe - centre).T) - radius).max() / radius)
    is_circle = deviation <= rel
    reason = "" if is_circle else (
        f"the window is not a circle: a vertex or edge midpoint lies {deviation:.3g} x radius from the "
        f"best-fit circle (tolerance {rel:g})"
    )
    return CircleWindow(is_circle, (float(centre[0]), float(centre[1])), radius, deviation, reason)


#: Default radius of circles placed in a window, as a fraction of the largest inscribed circle's: a
#: little room lets a second circle fit beside the first in a window about twice as long as wide.
INSCRIBED_RADIUS_FRACTION = 0.9


@dataclass(frozen=True)
class InscribedCircles:
    """Disjoint circles of one radius placed fully inside a window polygon.

    Attributes
    ----------
    centres_xy_m : (k, 2) ndarray of float64
        Circle centres (x, y) in metres, k >= 1.
    radius_m : float
        The common radius r in metres.
    largest_radius_m : float
        Radius of the window's largest inscribed circle (r <= this).
    """

    centres_xy_m: np.ndarray
    radius_m: float
    largest_radius_m: float

    @property
    def n_circles(self) -> int:
        """Number of circles k."""
        return int(self.centres_xy_m.shape[0])


def _window_polygon(window: Any, name: str = "window"):
    import shapely

    if isinstance(window, SamplingWindow):
        return window.polygon
    try:
        ring = _as_window(window)
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from exc
    if ring is None:
        raise ValueError(f"{name} is required: the polygon to place circles in")
    polygon = shapely.Polygon(ring)
    if not polygon.is_valid:
        raise ValueError(f"{name} is not a valid polygon (self-intersecting ring?)")
    return polygon


def inscribed_circles(window: Any, *, radius_m: float | None = None,
                      radius_fraction: float = INSCRIBED_RADIUS_FRACTION) -> InscribedCircles:
    r"""Disjoint circles of one radius, fully inside a window polygon, as many as a hexagonal grid fits.

    Parameters
    ----------
    window : (k, 2) array_like of float, shapely.Polygon or SamplingWindow
        The window (metres).
    radius_m : float, optional
        Circle radius, > 0 and at most the largest inscribed circle's. Default None:
        ``radius_fraction`` times the largest inscribed circle's radius.
    radius_fraction : float, default 0.9
        In (0, 1]; used when ``radius_m`` is None.

    Returns
    -------
    InscribedCircles
        At least one circle.

    Raises
    ------
    ValueError
        A bad window, a radius that does not fit (the message gives the largest that does), or a
        ``radius_fraction`` outside (0, 1].

    Notes
    -----
    The largest inscribed circle is GEOS's (``shapely.maximum_inscribed_circle``, the pole of
    inaccessibility). Centres of circles inside the window are the points of the window eroded by
    r; candidate centres form a hexagonal grid of spacing 2r (touching, never overlapping circles),
    anchored at the eroded region's lower-left corner and shifted by quarter spacings; the shift
    that keeps the most candidates wins, and the chosen pattern is then centred in the eroded
    region when it still fits. A W × H rectangle (W >= H) thus gets about W / H circles side by
    side. The circles are disjoint, so their counts are independent samples of one network.

    Examples
    --------
    >>> c = inscribed_circles([(0, 0), (20, 0), (20, 10), (0, 10)])
    >>> c.n_circles, round(c.radius_m, 9), c.centres_xy_m.round(9).tolist()
    (2, 4.5, [[5.5, 5.0], [14.5, 5.0]])
    """
    import shapely

    polygon = _window_polygon(window)
    largest = float(shapely.maximum_inscribed_circle(polygon, tolerance=1e-9 * math.sqrt(polygon.area)).length)
    if radius_m is None:
        fraction = _real(radius_fraction, "radius_fraction")
        if not 0.0 < fraction <= 1.0:
            raise ValueError(f"radius_fraction must be in (0, 1] (of the largest inscribed radius), got {fraction}")
        r = fraction * largest
    else:
        r = _real_at_least(radius_m, "radius_m", "circle radius in metres", above_zero=True)
        if r > largest * (1.0 + 1e-9):
            raise ValueError(f"radius_m = {r:g} does not fit in the window: its largest inscribed circle "
                             f"has radius {largest:g}")
    core = polygon.buffer(-r * (1.0 - 1e-12))
    if core.is_empty or core.area <= 0.0:
        centre = shapely.get_coordinates(shapely.maximum_inscribed_circle(polygon))[0]
        return InscribedCircles(centre[None, :].copy(), r, largest)
    xmin, ymin, xmax, ymax = core.bounds
    dx, dy = 2.0 * r, math.sqrt(3.0) * r
    best = None
    for fy in (0.0, 0.25, 0.5, 0.75):
        for fx in (0.0, 0.25, 0.5, 0.75):
            points = []
            for i, y in enumerate(np.arange(ymin + fy * dy, ymax + 1e-9 * dy, dy)):
                xs = np.arange(xmin + fx * dx + (i % 2) * r, xmax + 1e-9 * dx, dx)  # rows offset by r
                points.append(np.column_stack([xs, np.full(xs.size, y)]))
            grid = np.vstack(points) if points else np.zeros((0, 2))
            keep = grid[shapely.covers(core, shapely.points(grid))] if grid.size else grid
            if best is None or keep.shape[0] > best.shape[0]:
                best = keep
    if best.shape[0] == 0:  # a core thinner than the grid: its best point
        best = shapely.get_coordinates(shapely.maximum_inscribed_circle(polygon))[:1]
    shift = np.array([0.5 * (xmin + xmax), 0.5 * (ymin + ymax)]) - 0.5 * (best.min(axis=0) + best.max(axis=0))
    if shapely.covers(core, shapely.points(best + shift)).all():
        best = best + shift
    return InscribedCircles(np.ascontiguousarray(best, dtype=np.float64), r, largest)


@dataclass(frozen=True)
class MauldonCircles:
    r"""Mauldon's estimates pooled over k disjoint circles of one radius.

    Attributes
    ----------
    centres_xy_m : (k, 2) ndarray of float64
    radius_m : float
    n_intersections : (k,) ndarray of int64
        n_j per circle.
    n_endpoints : (k,) ndarray of int64
        m_j per circle.
    p21_per_m : float
        :math:`\sum n_j / (4 k r)` in m/m².
    p20_per_m2 : float
        :math:`\sum m_j / (2\pi k r^2)` in 1/m².
    mean_length_m : float
        :math:`(\pi r / 2) \sum n_j / \sum m_j` in metres; NaN when no end lies inside any circle.
    valid : bool
        Whether ``mean_length_m`` is defined.
    reason : str
        Why not ('' when valid).
    """

    centres_xy_m: np.ndarray
    radius_m: float
    n_intersections: np.ndarray
    n_endpoints: np.ndarray
    p21_per_m: float
    p20_per_m2: float
    mean_length_m: float
    valid: bool
    reason: str

    @property
    def n_circles(self) -> int:
        """Number of circles k."""
        return int(self.centres_xy_m.shape[0])


def mauldon_circles(trace_map: TraceMap, circles: InscribedCircles | None = None, *, window: Any = None,
                    tolerance_m: float = 0.0) -> MauldonCircles:
    r"""Mauldon's P21, P20 and mean trace length pooled over disjoint circles inside a window.

    Parameters
    ----------
    trace_map : TraceMap
        The traces.
    circles : InscribedCircles, optional
        Where to count; default None: :func:`inscribed_circles` of ``window`` (or of the map's window).
    window : array_like, shapely.Polygon or SamplingWindow, optional
        Used when ``circles`` is None.
    tolerance_m : float, default 0.0
        As in :func:`mauldon_circle`.

    Returns
    -------
    MauldonCircles

    Notes
    -----
    For k circles of radius r the counts add: :math:`E[\sum n_j] = 4 k r P_{21}` and
    :math:`E[\sum m_j] = 2 \pi k r^2 P_{20}` (Mauldon et al. 2001, eqs. 14 and 11 for each circle), so

    .. math:: \hat P_{21} = \frac{\sum n_j}{4 k r}, \quad \hat P_{20} = \frac{\sum m_j}{2\pi k r^2},
              \quad \hat\mu_L = \frac{\pi r}{2}\,\frac{\sum n_j}{\sum m_j}

    are unbiased (the first two) and consistent (the ratio) as for one circle, with the variance of
    k times the area; pooling counts rather than averaging per-circle ratios keeps
    :math:`\hat\mu_L` defined when a single circle has m = 0 (Rohrbaugh et al. 2002).

    References
    ----------
    .. [1] Mauldon, M., Dunne, W. M., Rohrbaugh, M. B. (2001). Circular scanlines and circular windows:
       new tools for characterizing the geometry of fracture traces. J. Struct. Geol. 23, 247-258.
    .. [2] Rohrbaugh, M. B., Dunne, W. M., Mauldon, M. (2002). Estimating fracture trace intensity,
       density, and mean length using circular scan lines and windows. AAPG Bulletin 86(12),
       2089-2104.

    Examples
    --------
    >>> tm = TraceMap.from_segments([[0, 5, 20, 5]], window=[(0, 0), (20, 0), (20, 10), (0, 10)])
    >>> e = mauldon_circles(tm)  # two circles of radius 4.5, each crossed twice
    >>> e.n_intersections.tolist(), round(e.p21_per_m, 12)
    ([2, 2], 0.111111111111)
    """
    _require_trace_map(trace_map)
    if circles is None:
        if window is None:
            if trace_map.window_xy_m is None:
                raise ValueError("give circles or a window: the trace map has no window to place circles in")
            window = trace_map.window_xy_m
        circles = inscribed_circles(window)
    elif not isinstance(circles, InscribedCircles):
        raise TypeError(f"circles must be an InscribedCircles, got {type(circles).__name__}")
    r = circles.radius_m
    counts = [mauldon_circle(trace_map, c, r, tolerance_m=tolerance_m) for c in circles.centres_xy_m]
    n = np.array([e.n_intersections for e in counts], dtype=np.int64)
    m = np.array([e.n_endpoints for e in counts], dtype=np.int64)
    k = n.size
    valid = int(m.sum()) > 0
    return MauldonCircles(
        centres_xy_m=circles.centres_xy_m.copy(),
        radius_m=r,
        n_intersections=n,
        n_endpoints=m,
        p21_per_m=float(n.sum()) / (4.0 * k * r),
        p20_per_m2=float(m.sum()) / (2.0 * math.pi * k * r * r),
        mean_length_m=0.5 * math.pi * r * float(n.sum()) / float(m.sum()) if valid else math.nan,
        valid=valid,
        reason="" if valid else (f"no trace end inside any of the {k} circle(s) (m = 0): the mean trace "
                                 "length is undefined"),
    )
