"""Trace intensity on a face or map: sampling window, P20, P21, raw mean length, scanline spacing.

This module owns the sampling window that every trace-map statistic shares (:func:`sampling_window`:
the explicit window, else the map's, else the traces' bounding box) and the window-based measures of
how densely a face is jointed:

=================  ==========  ======================================================================
measure            unit        definition (docs/fractures.md §5)
=================  ==========  ======================================================================
P20                1/m²        traces per window area (counting rule ``p20_rule``, see below)
P21                m/m²        trace length per window area, each trace clipped to the window
mean length        m           raw mean of the clipped trace lengths (no censoring correction)
P10                1/m         intersections per scanline length, scanlines normal to a set
mean spacing       m           scanline length / intersections = 1 / P10
=================  ==========  ======================================================================

P20 counting rules
------------------
``"endpoints"`` (default): every trace end that lies inside the window, farther than the edge
tolerance from its boundary, counts as half a trace, P20 = m / (2A). Ends on the boundary (traces
cut by the window, Sanderson & Nixon's E nodes) or outside it do not count. Each trace of a stationary
network has two ends, so m / 2 is an unbiased estimate of the number of traces per area whatever the
window censors; it is Mauldon's P20 = m / (2πc²) for any window shape, and fractopo's
``(I + Y) / 2`` traces per area.
``"midpoints"``: a trace counts once when the arc-length midpoint of the trace *as given* lies in the
window (boundary included). Unbiased when the traces extend uncut beyond the window; biased high when
they are already clipped to it (the midpoint of a clipped piece is always inside).

Tolerances: a tolerance below ``1e-9 ×`` the window's diameter is raised to that floor, so points
computed by clipping or intersection (exact only to the last bit) still count as on the boundary.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from .tracemap import TraceMap, _as_window, _require_trace_map

__all__ = ["SamplingWindow", "ScanlineSurvey", "TraceIntensity", "clipped_lengths_m", "sampling_window",
           "scanline_survey", "trace_intensity"]

#: Relative floor of every geometric tolerance (times the window or map diameter): clipping and
#: intersection give points exact to about 1e-16 relative; 1e-9 leaves a wide margin above rounding and
#: stays far below any digitising precision (a 10 m face: 10 nm).
ROUNDING_FRACTION = 1e-9

P20_RULES = ("endpoints", "midpoints")

WINDOW_SOURCES = ("argument", "trace_map", "bounding_box", "convex_hull")

#: The explicit stand-ins for an unrecorded window that :func:`sampling_window` accepts by name.
WINDOW_CHOICES = {"bbox": "bounding_box", "hull": "convex_hull"}

#: Number of scanlines laid across the window when no line spacing is given.
DEFAULT_SCANLINES = 10


# -- validation helpers shared by the trace-statistics modules ----------------------------------


def _real(value: Any, name: str) -> float:
    """``value`` as a finite float, or TypeError / ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value}")
    return value


def _real_at_least(value: Any, name: str, meaning: str, *, above_zero: bool = False) -> float:
    """``value`` as a finite float >= 0 (> 0 with ``above_zero``), else an error naming ``name``."""
    value = _real(value, name)
    if value < 0.0 or (above_zero and value == 0.0):
        raise ValueError(f"{name} must be {'>' if above_zero else '>='} 0 ({meaning}), got {value}")
    return value


def _integer_at_least(value: Any, name: str, minimum: int, meaning: str) -> int:
    """``value`` as an int >= ``minimum`` (bool is not an integer here), else an error naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer ({meaning}), got {type(value).__name__}")
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum} ({meaning}), got {value}")
    return int(value)


def _choice(value: Any, choices: tuple[str, ...], name: str) -> str:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value


def _endpoints_xy(trace_map: TraceMap) -> np.ndarray:
    """(n_traces, 2, 2) float64: ``[i, 0]`` is the first vertex of trace i, ``[i, 1]`` its last."""
    return np.stack([trace_map.xy_m[trace_map.offsets[:-1]], trace_map.xy_m[trace_map.offsets[1:] - 1]], axis=1)


def _floor_tolerance(tolerance_m: float, diameter_m: float) -> float:
    """``tolerance_m`` raised to the rounding floor ``ROUNDING_FRACTION * diameter_m``."""
    return max(tolerance_m, ROUNDING_FRACTION * diameter_m)


# -- the sampling window ------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SamplingWindow:
    """The polygon a trace map was sampled in, and where it came from.

    Attributes
    ----------
    polygon : shapely.Polygon
        Valid polygon without holes, coordinates in metres in the trace map's frame.
    source : {"argument", "trace_map", "bounding_box", "convex_hull"}
        Given explicitly, the map's own ``window_xy_m``, or the axis-aligned bounding box or the
        convex hull of the trace vertices (stand-ins when nobody recorded the window: they make the
        outermost traces look censored and P20, P21 high where the mapped area was larger).
    """

    polygon: shapely.Polygon
    source: str

    def __post_init__(self) -> None:
        if not isinstance(self.polygon, shapely.Polygon):
            raise TypeError(f"polygon must be a shapely Polygon, got {type(self.polygon).__name__}")
        _choice(self.source, WINDOW_SOURCES, "source")

    @property
    def area_m2(self) -> float:
        """Window area in m²."""
        return float(self.polygon.area)

    @property
    def diameter_m(self) -> float:
        """Diagonal of the window's bounding box in metres (the scale of its tolerances)."""
        xmin, ymin, xmax, ymax = self.polygon.bounds
        return float(math.hypot(xmax - xmin, ymax - ymin))

    @property
    def boundary(self) -> shapely.LineString:
        """The window's exterior ring."""
        return self.polygon.exterior


def sampling_window(trace_map: TraceMap, window: Any = None) -> SamplingWindow:
    """Resolve the sampling window of a trace map.

    Parameters
    ----------
    trace_map : TraceMap
        The traces.
    window : (k, 2) array_like of float, shapely.Polygon, SamplingWindow, "bbox" or "hull", optional
        Exterior ring of the window in metres (k >= 3, non-zero area, no holes, not
        self-intersecting); or ``"bbox"`` / ``"hull"``: the bounding box / convex hull of the trace
        vertices, chosen explicitly. Default None: the map's ``window_xy_m``, else the traces'
        bounding box (:func:`~rockmass.dfn.trace_map_statistics` refuses that silent default).

    Returns
    -------
    SamplingWindow
        The polygon and its ``source`` (``"argument"``, ``"trace_map"``, ``"bounding_box"`` or
        ``"convex_hull"``).

    Raises
    ------
    ValueError
        A bad window (the message names ``window``), or no window at all when the map is empty or its
        bounding box has zero area (all traces on one horizontal or vertical line).

    Examples
    --------
    >>> tm = TraceMap.from_segments([[0, 0, 4, 0], [1, -1, 1, 2]])
    >>> w = sampling_window(tm)
    >>> w.source, w.area_m2
    ('bounding_box', 12.0)
    """
    _require_trace_map(trace_map)
    if isinstance(window, SamplingWindow):
        return window
    if isinstance(window, str):
        _choice(window, tuple(WINDOW_CHOICES), "window")
        return _traces_hull(trace_map) if window == "hull" else _traces_box(trace_map)
    if window is not None:
        try:
            ring = _as_window(window)
        except ValueError as exc:
            raise ValueError(f"window: {exc}") from exc
        return SamplingWindow(_valid_polygon(ring, "window"), "argument")
    if trace_map.window_xy_m is not None:
        return SamplingWindow(_valid_polygon(trace_map.window_xy_m, "trace_map.window_xy_m"), "trace_map")
    return _traces_box(trace_map)


def _traces_box(trace_map: TraceMap) -> SamplingWindow:
    """The traces' axis-aligned bounding box as the window."""
    if trace_map.n_traces == 0:
        raise ValueError("window: an empty trace map (0 traces) has no bounding box; pass window=...")
    xmin, ymin, xmax, ymax = trace_map.bounds()
    if xmax <= xmin or ymax <= ymin:
        raise ValueError(
            "window: the map has no window and its traces' bounding box has zero area "
            f"(x {xmin}..{xmax}, y {ymin}..{ymax}); pass window=... (the sampled polygon)"
        )
    return SamplingWindow(shapely.box(xmin, ymin, xmax, ymax), "bounding_box")


def _traces_hull(trace_map: TraceMap) -> SamplingWindow:
    """The convex hull of the trace vertices as the window."""
    if trace_map.n_traces == 0:
        raise ValueError("window: an empty trace map (0 traces) has no convex hull; pass window=...")
    hull = shapely.convex_hull(shapely.multipoints(trace_map.xy_m))
    if not isinstance(hull, shapely.Polygon) or hull.area == 0.0:
        raise ValueError("window: the traces' convex hull has zero area (every vertex on one line); "
                         "pass window=... (the sampled polygon)")
    shapely.prepare(hull)
    return SamplingWindow(hull, "convex_hull")


def _valid_polygon(ring: np.ndarray, name: str) -> shapely.Polygon:
    polygon = shapely.Polygon(ring)
    if not polygon.is_valid:
        raise ValueError(f"{name} is not a valid polygon ({shapely.is_valid_reason(polygon)}); "
                         "give a simple, non-self-intersecting ring")
    shapely.prepare(polygon)
    return polygon


def _optional_window(trace_map: TraceMap, window: Any) -> SamplingWindow | None:
    """The explicit window, else the map's, else None (no bounding-box stand-in)."""
    if window is None and trace_map.window_xy_m is None:
        return None
    return sampling_window(trace_map, window)


# -- lengths and intensity ----------------------------------------------------------------------


def clipped_lengths_m(trace_map: TraceMap, window: Any = None) -> np.ndarray:
    """Length of each trace inside the window.

    Parameters
    ----------
    trace_map : TraceMap
        The traces.
    window : array_like, shapely.Polygon or SamplingWindow, optional
        As in :func:`sampling_window`. Default None (the map's window, else the bounding box).

    Returns
    -------
    (n_traces,) ndarray of float64
        :math:`|T_i \\cap W|` in metres; 0 for a trace outside the window.

    Examples
    --------
    >>> tm = TraceMap.from_segments([[-1, 1, 3, 1], [0.5, 0.5, 1.5, 0.5]])
    >>> clipped_lengths_m(tm, [(0, 0), (2, 0), (2, 2), (0, 2)])
    array([2., 1.])
    """
    window = sampling_window(trace_map, window)
    return _clipped_lengths(trace_map.to_shapely(), window.polygon)


def _clipped_lengths(lines: np.ndarray, polygon: shapely.Polygon) -> np.ndarray:
    lengths = shapely.length(lines)
    cut = ~shapely.covered_by(lines, polygon)  # only traces that leave the window need clipping
    lengths[cut] = shapely.length(shapely.intersection(lines[cut], polygon))
    return lengths


@dataclass(frozen=True)
class TraceIntensity:
    """P20, P21 and the raw mean trace length of the traces in one window.

    Attributes
    ----------
    window_source : str
        Where the window came from (see :class:`SamplingWindow`).
    area_m2 : float
        Window area A in m².
    n_traces : int
        Traces that intersect the window (boundary included).
    p20_rule : {"endpoints", "midpoints"}
        The counting rule (module docstring).
    trace_count : float
        The P20 numerator: m / 2 (``"endpoints"``; may be a half-integer) or the number of midpoints
        in the window (``"midpoints"``).
    p20_per_m2 : float
        P20 = trace_count / A in 1/m².
    total_length_m : float
        Sum of the clipped trace lengths in metres.
    p21_per_m : float
        P21 = total_length_m / A in m/m².
    mean_length_m : float
        Raw mean clipped length of the ``n_traces`` traces in metres; NaN (with ``mean_length_valid``
        False) when no trace reaches the window.
    mean_length_valid : bool
        Whether ``mean_length_m`` is defined.
    edge_tolerance_m : float
        Distance from the boundary within which an end counts as on the boundary (after the rounding
        floor).
    """

    window_source: str
    area_m2: float
    n_traces: int
    p20_rule: str
    trace_count: float
    p20_per_m2: float
    total_length_m: float
    p21_per_m: float
    mean_length_m: float
    mean_length_valid: bool
    edge_tolerance_m: float


def trace_intensity(
    trace_map: TraceMap, *, window: Any = None, p20_rule: str = "endpoints", edge_tolerance_m: float = 0.0
) -> TraceIntensity:
    r"""Areal frequency P20, intensity P21 and raw mean trace length in a window.

    Parameters
    ----------
    trace_map : TraceMap
        The traces (may be empty when a window is given).
    window : array_like, shapely.Polygon or SamplingWindow, optional
        As in :func:`sampling_window`. Default None (the map's window, else the bounding box).
    p20_rule : {"endpoints", "midpoints"}, default "endpoints"
        How traces are counted for P20 (module docstring).
    edge_tolerance_m : float, default 0.0
        Trace ends closer than this to the window boundary count as on it (censored, not counted by
        the ``"endpoints"`` rule); >= 0, raised to the rounding floor. Use the topology's snap
        tolerance so that P20 counts exactly the I and Y nodes.

    Returns
    -------
    TraceIntensity

    Notes
    -----
    .. math:: P_{20} = \frac{m}{2A}, \qquad P_{21} = \frac{1}{A}\sum_i |T_i \cap W|

    with m the trace ends strictly inside the window W of area A (docs/fractures.md §5, eq. (5.2); Mauldon et al.
    2001 for the end-counting estimator; Dershowitz & Herda 1992 for the P_ij notation).

    References
    ----------
    .. [1] Dershowitz, W. S., Herda, H. H. (1992). Interpretation of fracture spacing and intensity.
       33rd U.S. Symposium on Rock Mechanics, ARMA-92-0757.
    .. [2] Mauldon, M., Dunne, W. M., Rohrbaugh, M. B. (2001). Circular scanlines and circular windows:
       new tools for characterizing the geometry of fracture traces. J. Struct. Geol. 23, 247-258.

    Examples
    --------
    >>> tm = TraceMap.from_segments([[1, 1, 4, 5], [0, 2, 10, 2]])  # a 5 m trace, a 10 m one edge to edge
    >>> r = trace_intensity(tm, window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    >>> r.p21_per_m, r.trace_count, r.p20_per_m2, r.mean_length_m
    (0.15, 1.0, 0.01, 7.5)
    """
    _require_trace_map(trace_map)
    resolved = sampling_window(trace_map, window)
    p20_rule = _choice(p20_rule, P20_RULES, "p20_rule")
    tolerance = _floor_tolerance(
        _real_at_least(edge_tolerance_m, "edge_tolerance_m", "distance to the window edge in metres"),
        resolved.diameter_m,
    )
    polygon = resolved.polygon
    lines = trace_map.to_shapely()
    in_window = shapely.intersects(lines, polygon)
    lengths = _clipped_lengths(lines, polygon)
    if p20_rule == "endpoints":
        inside = _ends_strictly_inside(trace_map, resolved, tolerance)
        trace_count = 0.5 * int(np.count_nonzero(inside))
    else:
        midpoints = shapely.line_interpolate_point(lines, 0.5, normalized=True)
        trace_count = float(np.count_nonzero(shapely.covered_by(midpoints, polygon)))
    n_in = int(np.count_nonzero(in_window))
    area = resolved.area_m2
    total = float(lengths.sum())
    return TraceIntensity(
        window_source=resolved.source,
        area_m2=area,
        n_traces=n_in,
        p20_rule=p20_rule,
        trace_count=trace_count,
        p20_per_m2=trace_count / area,
        total_length_m=total,
        p21_per_m=total / area,
        mean_length_m=total / n_in if n_in else math.nan,
        mean_length_valid=n_in > 0,
        edge_tolerance_m=tolerance,
    )


def _ends_strictly_inside(trace_map: TraceMap, window: SamplingWindow, tolerance_m: float) -> np.ndarray:
    """(n_traces, 2) bool: trace ends inside the window and farther than ``tolerance_m`` from its edge."""
    ends = _endpoints_xy(trace_map).reshape(-1, 2)
    inside = shapely.contains_xy(window.polygon, ends[:, 0], ends[:, 1])
    near_edge = shapely.dwithin(window.boundary, shapely.points(ends), tolerance_m)
    return (inside & ~near_edge).reshape(-1, 2)


# -- scanlines ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class ScanlineSurvey:
    """Parallel virtual scanlines across a window and the traces they cross.

    Attributes
    ----------
    scanline_angle_deg : float
        Direction of the scanlines, 0-180° counter-clockwise from +x (normal to ``set_angle_deg``).
    set_angle_deg : float
        The set direction the scanlines are normal to.
    line_spacing_m : float
        Distance between neighbouring scanlines in metres.
    offsets_m : (n_lines,) ndarray of float64
        Position of each scanline along the set direction, measured from the origin of the frame.
    lengths_m : (n_lines,) ndarray of float64
        Length of each scanline inside the window.
    n_intersections : (n_lines,) ndarray of int64
        Trace crossings on each scanline.
    total_length_m : float
        Sum of ``lengths_m``.
    total_intersections : int
        Sum of ``n_intersections``.
    p10_per_m : float
        P10 = total_intersections / total_length_m in 1/m.
    mean_spacing_m : float
        total_length_m / total_intersections in metres; NaN (``valid`` False) with no intersection.
    valid : bool
        Whether ``mean_spacing_m`` is defined.
    reason : str
        Why it is not ('' when valid).
    """

    scanline_angle_deg: float
    set_angle_deg: float
    line_spacing_m: float
    offsets_m: np.ndarray
    lengths_m: np.ndarray
    n_intersections: np.ndarray
    total_length_m: float
    total_intersections: int
    p10_per_m: float
    mean_spacing_m: float
    valid: bool
    reason: str


def scanline_survey(
    trace_map: TraceMap,
    set_angle_deg: float,
    *,
    window: Any = None,
    line_spacing_m: float | None = None,
) -> ScanlineSurvey:
    r"""Mean spacing and P10 along parallel scanlines laid normal to a joint set.

    Parameters
    ----------
    trace_map : TraceMap
        The traces of one set (select them first, e.g. ``trace_map.subset(sets.membership == s)``).
    set_angle_deg : float
        Mean direction of the set, degrees counter-clockwise from +x (any real value; taken modulo 180).
    window : array_like, shapely.Polygon or SamplingWindow, optional
        As in :func:`sampling_window`. Give the window of the whole map when ``trace_map`` is a subset,
        or the subset's bounding box is used. Default None.
    line_spacing_m : float, optional
        Distance between scanlines, > 0. Default None: the window's width along the set direction
        divided by 10, so 10 scanlines cross it.

    Returns
    -------
    ScanlineSurvey

    Notes
    -----
    The scanlines run at :math:`\theta_s + 90°` and sit at offsets :math:`o_j` along the set direction
    :math:`\theta_s`, spaced ``line_spacing_m`` apart and centred on the window's extent. Each is clipped
    to the window (a concave window may cut it into pieces). With :math:`N` crossings of the set's
    traces over the clipped length :math:`L`:

    .. math:: P_{10} = N / L, \qquad \bar{s} = L / N.

    Traces are not corrected for their angle to the scanline (Terzaghi): within a set that angle is
    close to 90°, and the bias is :math:`1 / \overline{|\cos\delta|} - 1` (about 1.5 % for an axial
    spread of 10°). A trace lying along a scanline (a linear overlap) is not a crossing.

    References
    ----------
    .. [1] Priest, S. D. (1993). Discontinuity Analysis for Rock Engineering. Chapman & Hall, ch. 2
       (scanline sampling, spacing = 1 / P10).

    Examples
    --------
    >>> tm = TraceMap.from_segments([[0, y, 10, y] for y in (1, 3, 5, 7, 9)])  # 2 m apart
    >>> s = scanline_survey(tm, 0.0, window=[(0, 0), (10, 0), (10, 10), (0, 10)], line_spacing_m=2.5)
    >>> s.scanline_angle_deg, s.offsets_m.tolist(), s.mean_spacing_m, s.p10_per_m
    (90.0, [1.25, 3.75, 6.25, 8.75], 2.0, 0.5)
    """
    _require_trace_map(trace_map)
    angle = _real(set_angle_deg, "set_angle_deg") % 180.0
    resolved = sampling_window(trace_map, window)
    theta = math.radians(angle)
    along_set = np.array([math.cos(theta), math.sin(theta)])
    along_line = np.array([-math.sin(theta), math.cos(theta)])
    ring = shapely.get_coordinates(resolved.boundary)
    lo, hi = float((ring @ along_set).min()), float((ring @ along_set).max())
    reach_lo, reach_hi = float((ring @ along_line).min()), float((ring @ along_line).max())
    if line_spacing_m is None:
        spacing = (hi - lo) / DEFAULT_SCANLINES
    else:
        spacing = _real_at_least(
            line_spacing_m, "line_spacing_m", "distance between scanlines in metres", above_zero=True
        )
    n_lines = max(int(math.floor((hi - lo) / spacing)), 1)
    offsets = 0.5 * (lo + hi) + spacing * (np.arange(n_lines) - 0.5 * (n_lines - 1))
    margin = 1.0 + (reach_hi - reach_lo)  # the long lines overhang the window before clipping
    starts = offsets[:, None] * along_set + (reach_lo - margin) * along_line
    stops = offsets[:, None] * along_set + (reach_hi + margin) * along_line
    scanlines = shapely.intersection(shapely.linestrings(np.stack([starts, stops], axis=1)), resolved.polygon)
    lengths = shapely.length(scanlines)
    hits = _crossings_per_line(scanlines, trace_map.to_shapely())
    total_length, total_hits = float(lengths.sum()), int(hits.sum())
    valid = total_hits > 0
    return ScanlineSurvey(
        scanline_angle_deg=(angle + 90.0) % 180.0,
        set_angle_deg=angle,
        line_spacing_m=spacing,
        offsets_m=offsets,
        lengths_m=lengths,
        n_intersections=hits,
        total_length_m=total_length,
        total_intersections=total_hits,
        p10_per_m=total_hits / total_length if total_length > 0 else math.nan,
        mean_spacing_m=total_length / total_hits if valid else math.nan,
        valid=valid,
        reason="" if valid else "no trace of the set crosses the scanlines",
    )


def _crossings_per_line(scanlines: np.ndarray, traces: np.ndarray) -> np.ndarray:
    """(n_lines,) int64: point intersections of each scanline with the traces (overlaps excluded)."""
    counts = np.zeros(scanlines.size, dtype=np.int64)
    if traces.size == 0:
        return counts
    line_index, trace_index = shapely.STRtree(traces).query(scanlines, predicate="intersects")
    meet = shapely.intersection(scanlines[line_index], traces[trace_index])
    parts, pair = shapely.get_parts(meet, return_index=True)
    points = shapely.get_type_id(parts) == shapely.GeometryType.POINT
    np.add.at(counts, line_index[pair[points]], 1)
    return counts
