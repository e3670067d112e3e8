"""All trace-map statistics in one typed summary, written out under names a fractopo user recognises.

:func:`trace_map_statistics` resolves the sampling window once and runs, on the traces that reach it:
joint sets (:mod:`~rockmass.dfn.sets2d`), P20 / P21 / mean length and scanline spacing
(:mod:`~rockmass.dfn.intensity`), Mauldon's estimators on the window when it is a circle, else on
disjoint circles placed inside it (:mod:`~rockmass.dfn.mauldon`), and the I-Y-X-E topology
(:mod:`~rockmass.dfn.topology`). It returns a frozen
:class:`~rockmass.dfn.trace_summary.TraceMapStatistics`; each parameter is a
:class:`~rockmass.dfn.trace_summary.Parameter` (value or None, unit, and a reason when the value is
None). Its ``to_dict()`` is the JSON document, with the names and units of fractopo's ``Param``
(Ovaskainen et al. 2022); no NaN or infinity ever reaches it, so
``json.dumps(result.to_dict(), allow_nan=False)`` always succeeds.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely

from .frames import angle_convention, to_convention
from .intensity import (
    P20_RULES,
    _choice,
    SamplingWindow,
    TraceIntensity,
    _real_at_least,
    clipped_lengths_m,
    sampling_window,
    scanline_survey,
    trace_intensity,
)
from .mauldon import (
    CIRCLE_REL_TOLERANCE,
    CircleWindow,
    InscribedCircles,
    MauldonEstimate,
    circle_window,
    inscribed_circles,
    mauldon_circle,
    mauldon_circles,
)
from .sets2d import RESOLUTION_DEG, JointSets2D, fit_sets_2d, trace_angles_deg
from .topology import TraceTopology, trace_topology
from .trace_validation import SHARP_TURN_DEG, TraceValidation, validate_traces
from .trace_summary import (
    Diagnostics,
    IntensityParameters,
    MauldonCircleSet,
    MauldonParameters,
    NodeCounts,
    P21Map,
    Parameter,
    SetSelection,
    SetSummary,
    StatisticsSettings,
    TraceMapStatistics,
    TraceTable,
    ValidationSummary,
    WindowSummary,
    _number,
)
from .tracemap import TraceMap, _require_trace_map

__all__ = ["P21_MAP_CELLS", "p21_map", "trace_map_statistics"]

#: Default snap tolerance as a fraction of the window diameter: 1e-4 is 1 mm on a 10 m face and about
#: 0.7 px on a 24 MP photograph, close to fractopo's 1 mm default on outcrop maps of metres.
SNAP_FRACTION = 1e-4
#: Cells of the P21 map along the longer side of the window's bounding box (square cells): 10 gives
#: 100 cells or fewer, enough to see a trend across a face and still a few traces per cell.
P21_MAP_CELLS = 10
#: Segments cut at the grid lines per pass of the P21 map (bounds its memory, about 25 MB).
_P21_MAP_CHUNK = 100_000


def trace_map_statistics(
    trace_map: TraceMap,
    *,
    window: Any = None,
    n_sets: int | None = None,
    snap_tolerance_m: float | None = None,
    p20_rule: str = "endpoints",
    scanline_spacing_m: float | None = None,
    angle_method: str = "segments",
    resolution_deg: float = RESOLUTION_DEG,
    circle_rel_tolerance: float = CIRCLE_REL_TOLERANCE,
    mauldon_in_window: bool = True,
    seed: int = 0,
    length_unit: str = "m",
    sharp_turn_deg: float = SHARP_TURN_DEG,
) -> TraceMapStatistics:
    """Summarise a trace map: intensity, sets, Mauldon estimators, topology and trace lengths.

    Parameters
    ----------
    trace_map : TraceMap
        The traces, at least one reaching the window. Traces that miss the window are left out
        (counted under ``diagnostics``).
    window : array_like, shapely.Polygon, SamplingWindow, "bbox" or "hull", optional
        Sampling window (the mapped area): a polygon, or ``"bbox"`` / ``"hull"`` to take the traces'
        bounding box / convex hull, an explicit choice that ``result.window.source`` names. Default
        None: the map's own window; a map without one is an error (issue 19: the area is never
        chosen silently, it changes P20 and P21 by the ratio of the areas).
    n_sets : int, optional
        Number of joint sets; default None: chosen by BIC over 1..5.
    snap_tolerance_m : float, optional
        Snap distance for the topology and for ends on the window edge, >= 0. Default None:
        ``1e-4 ×`` the window diameter.
    p20_rule : {"endpoints", "midpoints"}, default "endpoints"
        P20 counting rule (see :mod:`rockmass.dfn.intensity`).
    scanline_spacing_m : float, optional
        Spacing of the scanlines laid normal to each set; default None: 10 scanlines per set.
    angle_method : {"segments", "chord"}, default "segments"
        Trace angle definition (see :func:`~rockmass.dfn.sets2d.trace_angles_deg`).
    resolution_deg, seed
        Passed to :func:`~rockmass.dfn.sets2d.fit_axial_mixture`.
    circle_rel_tolerance : float, default 0.01
        How close to a circle the window must be for Mauldon's estimators on the window itself
        (:func:`~rockmass.dfn.mauldon.circle_window`).
    mauldon_in_window : bool, default True
        When the window is not a circle, evaluate Mauldon's estimators on disjoint circles placed
        fully inside it (:func:`~rockmass.dfn.mauldon.inscribed_circles`, counts pooled by
        :func:`~rockmass.dfn.mauldon.mauldon_circles`); ``result.window.mauldon_circles``
        lists them. False: leave them undefined with a reason, as fractopo does.
    length_unit : str, default "m"
        Unit label of the map's coordinates (``"px"`` for a photo without scale); only the labels change.
    sharp_turn_deg : float, default 90.0
        Turn limit of fractopo's ``SHARP TURNS`` check (:func:`~rockmass.dfn.validate_traces`).

    Returns
    -------
    TraceMapStatistics
        Frozen, typed (:mod:`~rockmass.dfn.trace_summary`, documented field by field). Its
        ``to_dict()`` is JSON-ready, with parameters ``{"value", "unit"[, "reason"]}`` under their
        fractopo names: ``"Number of Traces"``, ``"Area"``, ``"Areal Frequency P20"``,
        ``"Fracture Intensity P21"``, ``"Trace Mean Length"``, ``"Trace Min Length"``,
        ``"Trace Max Length"``, ``"Dimensionless Intensity P22"``, ``"Number of Branches"``,
        ``"Connections per Trace"``, ``"Connections per Branch"``, ``"Connection Frequency"``,
        ``"Number of Censored Traces"``, ``"Fracture Intensity (Mauldon)"``,
        ``"Fracture Density (Mauldon)"``, ``"Trace Mean Length (Mauldon)"``; and

        - ``"Node Counts"``: ``{"I", "Y", "X", "E"}`` integers (``node_counts``);
        - ``"sets"``: one dict per joint set (mean angle, spread, κ, weight, count, P20, P21, mean
          length raw and Mauldon, mean spacing and P10 along scanlines normal to the set; ``sets``);
        - ``"set_selection"``: ``{"method": "bic" | "given", "bic": {k: value or None}}``;
        - ``"traces"``: per trace ``id``, clipped ``length``, ``censored``, ``set``, ``angle_deg``,
          ``connections``, ``end_class`` and ``validation_errors`` (fractopo's labels; the
          trace-length distribution with censoring marked; ``traces`` holds them as arrays);
        - ``"window"``: source, area, whether it is a circle (centre, radius), and the circles the
          Mauldon values were counted in when it is not (``"mauldon_circles"``: count, radius,
          centres; None when the window is a circle or ``mauldon_in_window`` is False);
        - ``"settings"``, ``"diagnostics"`` and ``"validation"``: how many traces fractopo's
          validation would flag, by label (:mod:`~rockmass.dfn.trace_validation`).

    Raises
    ------
    ValueError
        An empty map, a map without a window and no ``window``, no trace reaching the window, or a
        bad argument (the message names it).

    Notes
    -----
    Angles (per trace, set means, scanline directions) are given in the convention of the map's
    frame, ``result.angle_convention`` (:func:`~rockmass.dfn.frames.angle_convention`): azimuths
    clockwise from North, 0-180°, for a map (``frame == "map"``, as fractopo), counter-clockwise from
    +u, 0-180°, on a face or section. The set fit itself works on the axial angles either way.

    The trace lengths are those inside the window (clipped), so the raw mean length, P21 and the
    censored flags describe the same observations; the set fit weights each trace by that length.
    Connections per trace use Sanderson & Nixon's node-count :math:`N_L = (N_I + N_Y)/2`, as fractopo
    does, while "Number of Traces" is the observed count.

    References
    ----------
    .. [1] Ovaskainen, N., Nordbäck, N., Skyttä, P., Engström, J. (2022). A new subsampling methodology
       to optimize the characterization of two-dimensional bedrock fracture networks. J. Struct. Geol.
       155, 104528 (fractopo).

    Examples
    --------
    >>> tm = TraceMap.from_segments([[1, 5, 9, 5], [5, 1, 5, 9]], window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    >>> s = trace_map_statistics(tm)
    >>> s.intensity.p21, s.connections_per_trace.value
    (Parameter(value=0.16, unit='m/m²', reason=None), 1.0)
    >>> d = s.to_dict()
    >>> d["Fracture Intensity P21"], d["Node Counts"]
    ({'value': 0.16, 'unit': 'm/m²'}, {'I': 4, 'Y': 0, 'X': 1, 'E': 0})
    """
    resolution_deg, scanline_spacing_m = _checked_arguments(
        trace_map, length_unit, p20_rule, resolution_deg, scanline_spacing_m
    )
    resolved, traces = _traces_in_window(trace_map, window)
    tolerance = _snap_tolerance(snap_tolerance_m, resolved)
    circle, circles = _mauldon_windows(resolved, circle_rel_tolerance, mauldon_in_window)

    topology = trace_topology(traces, snap_tolerance_m=tolerance, window=resolved)
    validation = validate_traces(traces, snap_tolerance_m=tolerance, sharp_turn_deg=sharp_turn_deg)
    overall = trace_intensity(traces, window=resolved, p20_rule=p20_rule, edge_tolerance_m=tolerance)
    lengths = clipped_lengths_m(traces, resolved)
    angles = trace_angles_deg(traces, method=angle_method)
    sets = _fit_sets(traces, angles, lengths, n_sets, angle_method, resolution_deg, seed)
    u = _Units(length_unit)
    convention = angle_convention(trace_map.frame)
    membership, set_summaries, selection = _set_results(
        traces, sets, resolved, p20_rule, tolerance, scanline_spacing_m, circle, circles, u, convention
    )
    return TraceMapStatistics(
        n_traces=Parameter.of(traces.n_traces, "-"),
        area=Parameter.of(overall.area_m2, u.area),
        intensity=_intensity_parameters(overall, lengths, u),
        p22=Parameter.of(overall.p21_per_m * overall.mean_length_m, "-"),
        n_branches=Parameter.of(topology.n_branches, "-"),
        connections_per_trace=Parameter.of(
            topology.connections_per_line, "-", "no I or Y node: every trace end is censored (E)"
        ),
        connections_per_branch=Parameter.of(topology.connections_per_branch, "-", "no branch (no I, Y or X node)"),
        connection_frequency=Parameter.of((topology.n_y + topology.n_x) / overall.area_m2, u.per_area),
        n_censored=Parameter.of(int(topology.censored.sum()), "-"),
        mauldon=_mauldon_parameters(traces, circle, circles, tolerance, u),
        node_counts=NodeCounts(topology.n_i, topology.n_y, topology.n_x, topology.n_e),
        sets=set_summaries,
        set_selection=selection,
        traces=_trace_table(traces, lengths, topology, membership, angles, convention, validation, u),
        window=_window_summary(resolved, overall, circle, circles, u),
        settings=_statistics_settings(
            topology, p20_rule, angle_method, n_sets, resolution_deg, mauldon_in_window, seed,
            scanline_spacing_m, u,
        ),
        frame=trace_map.frame,
        crs=trace_map.crs,
        angle_convention=convention,
        diagnostics=_diagnostics(trace_map, traces, topology),
        p21_map=p21_map(traces, resolved, unit=u.length),
        validation=_validation_summary(validation, u),
    )


def p21_map(trace_map: TraceMap, window: Any, *, cells: int = P21_MAP_CELLS, unit: str = "m") -> P21Map:
    """P21 on a grid of square cells over the window: trace length per cell area.

    Parameters
    ----------
    trace_map : TraceMap
        The traces (their parts outside the window are left out).
    window : array_like, shapely.Polygon or SamplingWindow
        The sampling window (:func:`~rockmass.dfn.intensity.sampling_window`).
    cells : int, default :data:`P21_MAP_CELLS`
        Cells along the longer side of the window's bounding box, >= 1; the cells are square, so the
        shorter side gets ``ceil(short / s)`` of them.
    unit : str, default "m"
        The map's length unit (labels only).

    Returns
    -------
    P21Map
        ``length`` and ``area`` per cell (row 0 at the bottom) and ``p21 = length / area`` (NaN for
        a cell whose area inside the window is below 1e-9 of a whole cell).

    Notes
    -----
    Each straight segment of a clipped trace is cut at every grid line it crosses, and each piece
    goes to the cell holding its midpoint (half-open cells), so ``length.sum()`` is the total length
    inside the window up to rounding, even for a trace lying along a grid line, and
    ``length.sum() / area.sum()`` is the map's P21 (docs/fractures.md §5, eq. (5.1); Dershowitz &
    Herda 1992). A cell cut by the
    window edge has a small area and a noisy P21.

    Examples
    --------
    >>> tm = TraceMap.from_segments([[0, 5, 10, 5]], window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    >>> grid = p21_map(tm, tm.window_xy_m, cells=2)
    >>> grid.length.tolist(), grid.p21.tolist()
    ([[0.0, 0.0], [5.0, 5.0]], [[0.0, 0.0], [0.2, 0.2]])
    """
    if isinstance(cells, (bool, np.bool_)) or not isinstance(cells, (int, np.integer)) or cells < 1:
        raise ValueError(f"cells must be an integer >= 1 (cells along the window's longer side), got {cells!r}")
    polygon = sampling_window(trace_map, window).polygon
    x0, y0, x1, y1 = polygon.bounds
    side = max(x1 - x0, y1 - y0) / int(cells)
    nx = max(1, int(np.ceil((x1 - x0) / side - 1e-9)))
    ny = max(1, int(np.ceil((y1 - y0) / side - 1e-9)))
    xs, ys = x0 + side * np.arange(nx + 1), y0 + side * np.arange(ny + 1)
    col, row = np.meshgrid(np.arange(nx), np.arange(ny))
    boxes = shapely.box(xs[col], ys[row], xs[col + 1], ys[row + 1])
    area = shapely.area(shapely.intersection(boxes, polygon))
    lines = trace_map.to_shapely()
    cut = ~shapely.covered_by(lines, polygon)  # only traces that leave the window need clipping
    lines[cut] = shapely.intersection(lines[cut], polygon)
    parts = shapely.get_parts(lines)
    lines = parts[np.isin(shapely.get_type_id(parts), (1, 2))]  # LineString / LinearRing; no points
    coords, owner = shapely.get_coordinates(lines, return_index=True)
    same = owner[1:] == owner[:-1]
    starts, ends = coords[:-1][same], coords[1:][same]
    length = np.zeros(nx * ny)
    for k in range(0, starts.shape[0], _P21_MAP_CHUNK):
        cell, piece = _cut_at_grid(starts[k:k + _P21_MAP_CHUNK], ends[k:k + _P21_MAP_CHUNK], xs, ys)
        col_i = np.clip(np.floor((cell[:, 0] - x0) / side), 0, nx - 1).astype(np.int64)
        row_j = np.clip(np.floor((cell[:, 1] - y0) / side), 0, ny - 1).astype(np.int64)
        length += np.bincount(row_j * nx + col_i, weights=piece, minlength=nx * ny)
    length = length.reshape(ny, nx)
    with np.errstate(divide="ignore", invalid="ignore"):
        p21 = np.where(area > 1e-9 * side * side, length / area, np.nan)
    return P21Map((float(x0), float(y0)), float(side), length, area, p21, unit)


def _cut_at_grid(a: np.ndarray, b: np.ndarray, xs: np.ndarray, ys: np.ndarray):
    """Segments a→b cut at the grid lines x = xs and y = ys: (midpoints (m, 2), lengths (m,)).

    The cut parameters t of each segment (0, 1 and every crossing strictly inside) are sorted, and
    consecutive ones bound a piece; the pieces of a segment add up to its length.
    """
    d = b - a
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.concatenate([(xs[None, :] - a[:, :1]) / d[:, :1], (ys[None, :] - a[:, 1:]) / d[:, 1:]], axis=1)
    t = np.where((t > 0.0) & (t < 1.0), t, np.nan)
    t = np.sort(np.concatenate([np.zeros((a.shape[0], 1)), t, np.ones((a.shape[0], 1))], axis=1), axis=1)
    t = np.where(np.isnan(t), 1.0, t)                      # unused slots (NaN, sorted last) -> empty pieces
    dt = np.diff(t, axis=1)
    seg, piece = np.nonzero(dt > 0.0)
    mid = t[seg, piece] + 0.5 * dt[seg, piece]
    return a[seg] + mid[:, None] * d[seg], dt[seg, piece] * np.hypot(d[seg, 0], d[seg, 1])


class _Units:
    """Unit labels built from the map's length unit."""

    def __init__(self, length: str) -> None:
        self.length = length
        self.area = f"{length}²"
        self.intensity = f"{length}/{length}²"
        self.per_area = f"1/{length}²"
        self.per_length = f"1/{length}"


def _checked_arguments(
    trace_map: TraceMap, length_unit: str, p20_rule: str, resolution_deg: float,
    scanline_spacing_m: float | None,
) -> tuple[float, float | None]:
    """Check the map and the scalar arguments; ``(resolution_deg, scanline_spacing_m)`` as floats.

    Raises on a value that is not a :class:`TraceMap`, an empty map, a blank ``length_unit``, an
    unknown ``p20_rule``, or a resolution or scanline spacing that is not a positive number.
    """
    _require_trace_map(trace_map)
    if trace_map.n_traces == 0:
        raise ValueError("trace_map has 0 traces: there is nothing to analyse")
    if not isinstance(length_unit, str) or not length_unit.strip():
        raise TypeError(f"length_unit must be a non-empty string such as 'm' or 'px', got {length_unit!r}")
    _choice(p20_rule, P20_RULES, "p20_rule")
    resolution_deg = _real_at_least(
        resolution_deg, "resolution_deg", "angular resolution in degrees", above_zero=True
    )
    if scanline_spacing_m is not None:
        scanline_spacing_m = _real_at_least(
            scanline_spacing_m, "scanline_spacing_m", "distance between scanlines", above_zero=True
        )
    return resolution_deg, scanline_spacing_m


def _traces_in_window(trace_map: TraceMap, window: Any) -> tuple[SamplingWindow, TraceMap]:
    """The resolved sampling window and the traces that reach it (``trace_map`` itself when all do).

    The area is never chosen silently: a map without a window needs ``window`` (issue 19).
    """
    if window is None and trace_map.window_xy_m is None:
        raise ValueError(
            "window: the trace map has no sampling window (the mapped area) and none was given; pass "
            "window=<polygon> (the area that was mapped), or window='bbox' / window='hull' to take "
            "the traces' bounding box / convex hull (P20 and P21 scale with 1 / area)")
    resolved = sampling_window(trace_map, window)
    reaches = shapely.intersects(trace_map.to_shapely(), resolved.polygon)
    if not reaches.any():
        raise ValueError(f"none of the {trace_map.n_traces} traces reaches the window (source: {resolved.source})")
    traces = trace_map if reaches.all() else trace_map.subset(reaches)
    return resolved, traces


def _snap_tolerance(snap_tolerance_m: float | None, resolved: SamplingWindow) -> float:
    """The snap tolerance: ``snap_tolerance_m`` checked, or :data:`SNAP_FRACTION` × the window diameter."""
    if snap_tolerance_m is None:
        return SNAP_FRACTION * resolved.diameter_m
    return _real_at_least(snap_tolerance_m, "snap_tolerance_m", "snap distance in metres")


def _mauldon_windows(
    resolved: SamplingWindow, circle_rel_tolerance: float, mauldon_in_window: bool
) -> tuple[CircleWindow, InscribedCircles | None]:
    """Where Mauldon's estimators are evaluated: the window's circle fit, and the disjoint circles
    inside it when it is not a circle and ``mauldon_in_window`` is True (else None)."""
    circle = circle_window(resolved.polygon, rel_tolerance=circle_rel_tolerance)
    if not isinstance(mauldon_in_window, (bool, np.bool_)):
        raise TypeError(f"mauldon_in_window must be True or False, got {mauldon_in_window!r}")
    circles = inscribed_circles(resolved) if (mauldon_in_window and not circle.is_circle) else None
    return circle, circles


def _fit_sets(traces, angles, lengths, n_sets, angle_method, resolution_deg, seed) -> JointSets2D | str:
    """The set fit, or the reason there is none (no trace with a direction inside the window)."""
    if not np.any(np.isfinite(angles) & (lengths > 0.0)):
        return "no trace with a direction has a positive length inside the window"
    return fit_sets_2d(
        traces, n_sets, weights=lengths, method=angle_method, resolution_deg=resolution_deg, seed=seed
    )


def _set_results(
    traces, sets: JointSets2D | str, window, p20_rule, tolerance, spacing, circle, circles, u, convention
) -> tuple[np.ndarray, tuple[SetSummary, ...], SetSelection]:
    """Per-trace set index, one summary per set and how the sets were chosen; for a fit that could not
    be made (``sets`` is then its reason), every trace in set -1, no summary, and the reason."""
    if isinstance(sets, JointSets2D):
        membership = sets.membership
        set_summaries = tuple(
            _set_summary(
                traces, sets, s, window, p20_rule, tolerance, spacing, circle, circles, u, convention
            )
            for s in range(sets.n_sets)
        )
        selection = SetSelection(sets.selected_by, {str(k): _number(v) for k, v in sets.bic.items()})
    else:
        membership = np.full(traces.n_traces, -1, dtype=np.int64)
        set_summaries = ()
        selection = SetSelection(None, {}, sets)
    return membership, set_summaries, selection


def _intensity_parameters(intensity, lengths: np.ndarray, u: _Units) -> IntensityParameters:
    reaching = lengths[lengths > 0.0]
    none = "no trace has a positive length inside the window"
    return IntensityParameters(
        p20=Parameter.of(intensity.p20_per_m2, u.per_area),
        p21=Parameter.of(intensity.p21_per_m, u.intensity),
        mean_length=Parameter.of(intensity.mean_length_m, u.length, none),
        min_length=Parameter.of(reaching.min() if reaching.size else None, u.length, none),
        max_length=Parameter.of(reaching.max() if reaching.size else None, u.length, none),
    )


def _mauldon_parameters(
    traces: TraceMap, circle, circles: InscribedCircles | None, tolerance: float, u: _Units
) -> MauldonParameters:
    """Mauldon's values on the window when it is a circle, else pooled over ``circles`` (if any)."""
    units = (u.intensity, u.per_area, u.length)
    if circle.is_circle:
        estimate: MauldonEstimate = mauldon_circle(traces, circle.centre_xy_m, circle.radius_m, tolerance_m=tolerance)
    elif circles is not None:
        estimate = mauldon_circles(traces, circles, tolerance_m=tolerance)
    else:
        return MauldonParameters(*(Parameter.of(None, unit, circle.reason) for unit in units))
    values = (estimate.p21_per_m, estimate.p20_per_m2, estimate.mean_length_m)
    return MauldonParameters(*(Parameter.of(v, unit, estimate.reason) for v, unit in zip(values, units)))


def _set_summary(
    traces, sets: JointSets2D, s: int, window, p20_rule, tolerance, spacing, circle, circles, u, convention
) -> SetSummary:
    members = traces.subset(sets.membership == s)
    intensity = trace_intensity(members, window=window, p20_rule=p20_rule, edge_tolerance_m=tolerance)
    survey = scanline_survey(members, float(sets.mean_angle_deg[s]), window=window, line_spacing_m=spacing)
    lengths = clipped_lengths_m(members, window)
    return SetSummary(
        index=s,
        mean_angle=Parameter.of(float(to_convention(sets.mean_angle_deg[s], convention)), "deg"),
        circular_spread=Parameter.of(sets.spread_deg[s], "deg", "the set has no preferred direction"),
        kappa=Parameter.of(sets.kappa[s], "-"),
        kappa_capped=bool(sets.kappa_capped[s]),
        weight=Parameter.of(sets.weight[s], "-"),
        n_traces=Parameter.of(int(sets.count[s]), "-"),
        intensity=_intensity_parameters(intensity, lengths, u),
        mauldon=_mauldon_parameters(members, circle, circles, tolerance, u),
        mean_spacing=Parameter.of(survey.mean_spacing_m, u.length, survey.reason),
        scanline_p10=Parameter.of(survey.p10_per_m, u.per_length, "the scanlines have zero length"),
        scanline_angle=Parameter.of(float(to_convention(survey.scanline_angle_deg, convention)), "deg"),
        scanline_count=Parameter.of(int(survey.offsets_m.size), "-"),
        scanline_length=Parameter.of(survey.total_length_m, u.length),
        scanline_intersections=Parameter.of(survey.total_intersections, "-"),
    )


def _trace_table(
    traces: TraceMap, lengths: np.ndarray, topology: TraceTopology, membership: np.ndarray,
    angles: np.ndarray, convention: str, validation: TraceValidation, u: _Units,
) -> TraceTable:
    """The per-trace table: clipped lengths, topology, set index, angles in ``convention`` and labels."""
    return TraceTable(
        id=traces.attributes["id"].copy(),
        length=lengths,
        unit=u.length,
        censored=topology.censored,
        set_id=membership,
        angle_deg=to_convention(angles, convention),
        connections=topology.connections,
        end_class=topology.end_class,
        validation_errors=tuple(validation.errors()),
    )


def _window_summary(
    resolved: SamplingWindow, overall: TraceIntensity, circle: CircleWindow, circles: InscribedCircles | None,
    u: _Units,
) -> WindowSummary:
    """The window: its source and area, its circle fit, and the circles Mauldon's counts were pooled in."""
    return WindowSummary(
        source=resolved.source,
        area=overall.area_m2,
        unit=u.length,
        is_circle=circle.is_circle,
        centre_xy=tuple(circle.centre_xy_m) if circle.is_circle else None,
        radius=circle.radius_m if circle.is_circle else None,
        circle_deviation=_number(circle.max_rel_deviation),
        mauldon_circles=None if circles is None else MauldonCircleSet(
            circles.n_circles, circles.radius_m, circles.centres_xy_m
        ),
    )


def _statistics_settings(
    topology: TraceTopology, p20_rule: str, angle_method: str, n_sets: int | None, resolution_deg: float,
    mauldon_in_window: bool, seed: int, scanline_spacing_m: float | None, u: _Units,
) -> StatisticsSettings:
    """The settings used, defaults resolved (the snap tolerance as the topology applied it)."""
    return StatisticsSettings(
        snap_tolerance=Parameter.of(topology.snap_tolerance_m, u.length),
        p20_rule=p20_rule,
        angle_method=angle_method,
        n_sets=_number(n_sets),
        resolution_deg=resolution_deg,
        mauldon_in_window=bool(mauldon_in_window),
        seed=_number(seed),
        scanline_spacing=None if scanline_spacing_m is None else Parameter.of(scanline_spacing_m, u.length),
    )


def _diagnostics(trace_map: TraceMap, traces: TraceMap, topology: TraceTopology) -> Diagnostics:
    """Counts that flag suspicious input: traces outside the window, degenerate traces, end contacts
    and overlapping pairs."""
    return Diagnostics(
        traces_outside_window=int(trace_map.n_traces - traces.n_traces),
        zero_length_traces=int(np.count_nonzero(traces.degenerate_traces())),
        end_contacts=int(topology.end_contact.sum()),
        overlapping_pairs=topology.n_overlapping_pairs,
    )


def _validation_summary(validation: TraceValidation, u: _Units) -> ValidationSummary:
    """How many traces fractopo's validation would flag, by label."""
    return ValidationSummary(
        n_flagged=validation.n_flagged,
        counts=validation.counts(),
        sharp_turn_deg=validation.sharp_turn_deg,
        snap_tolerance=Parameter.of(validation.snap_tolerance_m, u.length),
    )
