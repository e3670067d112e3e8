"""Trace validation as fractopo reports it: each defect of each trace under fractopo's label.

fractopo (``fractopo.tval``, Ovaskainen et al. 2022) refuses to analyse a trace map until its
traces pass validation, and lists each trace's defects in a ``VALIDATION_ERRORS`` column.
:func:`validate_traces` flags the defects below that can be found cheaply (an STRtree of the traces,
vectorised shapely), under fractopo's labels, so a map written by rockmass shows a fractopo user
what fractopo will complain about. It never changes a trace: a trace is flagged, not dropped or
moved (the geometry is the user's).

=============================  ====================================================================
label (fractopo's)             flagged when
=============================  ====================================================================
``GEOM TYPE MULTILINESTRING``  the trace is one part of a MultiLineString feature whose parts do
                               not join (the readers split it, numbering ``part`` >= 0)
``CUTS ITSELF``                the trace is not simple (it crosses or touches itself) or is closed
``SHARP TURNS``                a segment turns by more than ``sharp_turn_deg`` from the previous
                               segment or from the trace's chord (first to last vertex), or has zero
                               length, or the chord has zero length
``V NODE``                     a trace end is within 1.1 τ of another trace's end (two traces meet
                               end to end, or nearly)
``MULTI JUNCTION``             a node (crossing point, or an end that is not on another trace) is
                               within 1.1 τ of two or more nodes of other traces: three or more
                               traces meet at a point, or two crossings nearly coincide
``MULTIPLE CROSSCUTS``         two traces cross at more than two points
``STACKED TRACES``             two traces share a linear stretch (digitised twice)
``UNDERLAPPING SNAP``          a trace end is farther than τ but within 1.1 τ of another trace it
                               does not reach (``OVERLAPPING SNAP``: of one it crosses), and within
                               τ of none
=============================  ====================================================================

τ is the snap tolerance of the topology (:func:`~rockmass.dfn.topology.trace_topology`) and 1.1 is
fractopo's ``SNAP_THRESHOLD_ERROR_MULTIPLIER``. As in fractopo's ``determine_general_nodes``, a
trace's crossing points at an end of it that touches another trace's end (within 1e-4) are not
nodes (that end is one, for V NODE), and an end within 1e-3 of one of its own trace's crossing
points is not an end node; these are fractopo's fixed distances, in the map's unit (metres on a
map): an end that overshoots a trace by more than 1e-3 but less than 1.1 τ is a MULTI JUNCTION, as
fractopo reports a slightly overlapping trace.

``SHARP TURNS`` follows fractopo's ``SharpCornerValidator``: its thresholds (135° from the chord,
100° from the previous segment) apply only after a test that fails any pair of directions more than
90° apart, so with its defaults both limits are 90°, the default of ``sharp_turn_deg`` here. A turn
of exactly the limit is not beyond it (fractopo's ``deg_angle > threshold_angle``), wherever the
traces lie: a turn counts only if it passes the limit by more than the rounding of the coordinates
can turn it (:func:`_sharp_turns`), so the exact 90° turns of a pixel staircase get the same label in
the face frame and on a UTM map. fractopo's own arithmetic decides such turns by rounding (it flags a
diagonal zig-zag of pixel steps (1, 1), (1, -1) and not an axis-aligned staircase), so on pixel
staircases its count can exceed this one.

Not checked: ``NULL GEOMETRY`` (the readers refuse it), ``TRACE UNDERLAPS TARGET AREA``,
``EMPTY TARGET AREA``, and the buffered part of ``STACKED TRACES`` (fractopo also flags stretches
that run within a buffer of another trace without touching it, and small triangles where two traces
cross twice). Measured against fractopo 0.9.2 with the same snap threshold
(``benchmarks/fractopo_crosscheck.py``): the 78 traces extracted from the quickstart photo before
session 24 get the same labels trace by trace (14 flagged: 13 SHARP TURNS, 2 V NODE); on the
quickstart photo of session 24, two traces that overlap each other get other labels and Y nodes
than fractopo gives them; on maps dense with defects UNDERLAPPING SNAP counts differ and the
buffered STACKED TRACES are missed (docs/fractures.md §9.1).

References
----------
.. [1] Ovaskainen, N., Nordbäck, N., Skyttä, P., Engström, J. (2022). A new subsampling methodology
   to optimize the characterization of two-dimensional bedrock fracture networks (fractopo).
   J. Struct. Geol. 155, 104528; validation rules in ``fractopo/tval/trace_validators.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from .intensity import _endpoints_xy, _floor_tolerance, _real_at_least
from .topology import _pair_intersections
from .tracemap import TraceMap, _require_trace_map

__all__ = ["TraceValidation", "validate_traces"]  # constants: import them by module

#: fractopo's labels, in the order they are listed per trace.
LABELS = ("GEOM TYPE MULTILINESTRING", "CUTS ITSELF", "SHARP TURNS", "V NODE", "MULTI JUNCTION",
          "MULTIPLE CROSSCUTS", "STACKED TRACES", "UNDERLAPPING SNAP", "OVERLAPPING SNAP")
#: fractopo's ``Validation.SNAP_THRESHOLD_ERROR_MULTIPLIER``: snapping errors are looked for out to
#: 1.1 τ.
SNAP_ERROR_MULTIPLIER = 1.1
#: Default turn limit: fractopo's effective limit with its default thresholds (module docstring).
SHARP_TURN_DEG = 90.0
#: fractopo's fixed distances of ``determine_general_nodes`` (the ``atol`` of its ``np.isclose``
#: tests), in the map's unit: two trace ends touch, and an end lies on a crossing point.
_ENDS_TOUCH, _ON_CROSSING = 1e-4, 1e-3
#: SHARP TURNS: a turn within the rounding of the coordinates of the limit is at the limit
#: (:func:`_sharp_turns`): the rounding bound's factor, and the least and largest tolerance in
#: degrees (the least covers the arithmetic of the angle, the largest keeps fractopo's label for any
#: turn farther from the limit, however short its segments).
_TURN_ROUNDING, _TURN_TOLERANCE_DEG, _TURN_TOLERANCE_MAX_DEG = 4.0, 1e-6, 1e-3


def errors_text(errors) -> np.ndarray:
    """(n_traces,) str: each trace's labels as fractopo writes its ``VALIDATION_ERRORS`` column to a
    file, the text of a Python tuple (``"('SHARP TURNS', 'V NODE')"``; ``"()"`` for a clean trace).

    >>> errors_text([("SHARP TURNS",), ()]).tolist()
    ["('SHARP TURNS',)", '()']
    """
    return np.array([str(tuple(labels)) for labels in errors], dtype=str)


@dataclass(frozen=True)
class TraceValidation:
    """fractopo-style defects of every trace.

    Attributes
    ----------
    flags : (n_traces, len(LABELS)) bool ndarray
        ``flags[i, k]``: trace i has the defect ``LABELS[k]``.
    snap_tolerance_m : float
        The snap tolerance τ used.
    sharp_turn_deg : float
        The turn limit of ``SHARP TURNS``.
    """

    flags: np.ndarray
    snap_tolerance_m: float
    sharp_turn_deg: float

    def errors(self) -> list[tuple[str, ...]]:
        """Per trace, the labels of its defects (an empty tuple for a clean trace)."""
        return [tuple(label for label, bad in zip(LABELS, row) if bad) for row in self.flags.tolist()]

    def counts(self) -> dict[str, int]:
        """Traces flagged with each label (every label, zeros included)."""
        return {label: int(n) for label, n in zip(LABELS, self.flags.sum(axis=0).tolist())}

    @property
    def n_flagged(self) -> int:
        """Traces with at least one defect."""
        return int(np.count_nonzero(self.flags.any(axis=1)))


def validate_traces(trace_map: TraceMap, *, snap_tolerance_m: float,
                    sharp_turn_deg: float = SHARP_TURN_DEG) -> TraceValidation:
    """Flag each trace's defects under fractopo's validation labels.

    Parameters
    ----------
    trace_map : TraceMap
        The traces; not modified.
    snap_tolerance_m : float
        Snap tolerance τ >= 0 in metres (raised, as in the topology, to 1e-9 of the map's diameter).
    sharp_turn_deg : float, default 90.0
        Largest turn, in degrees (0, 180], from the previous segment or from the chord.

    Returns
    -------
    TraceValidation

    Notes
    -----
    The rules, and how they follow fractopo's validators, are in the module docstring.

    Examples
    --------
    A straight trace, a zig-zag that doubles back (turns of 135°), and two traces meeting end to end:

    >>> tm = TraceMap.from_polylines([[(0, 0), (4, 0)], [(0, 2), (2, 2), (1, 3), (3, 3)],
    ...                               [(6, 0), (7, 1)], [(7, 1), (8, 0)]])
    >>> validate_traces(tm, snap_tolerance_m=0.01).errors()
    [(), ('SHARP TURNS',), ('V NODE',), ('V NODE',)]
    """
    _require_trace_map(trace_map)
    tau = _real_at_least(snap_tolerance_m, "snap_tolerance_m", "snap distance in metres")
    turn = _real_at_least(sharp_turn_deg, "sharp_turn_deg", "turn limit in degrees", above_zero=True)
    if turn > 180.0:
        raise ValueError(f"sharp_turn_deg must be in (0, 180] (a turn in degrees), got {sharp_turn_deg!r}")
    n = trace_map.n_traces
    if n:
        xmin, ymin, xmax, ymax = trace_map.bounds()
        tau = _floor_tolerance(tau, math.hypot(xmax - xmin, ymax - ymin))
    flags = np.zeros((n, len(LABELS)), dtype=bool)
    column = {label: k for k, label in enumerate(LABELS)}
    if n == 0:
        return TraceValidation(flags, tau, turn)
    lines = trace_map.to_shapely()
    if "part" in trace_map.attributes:
        flags[:, column["GEOM TYPE MULTILINESTRING"]] = np.asarray(trace_map.attributes["part"]) >= 0
    flags[:, column["CUTS ITSELF"]] = ~shapely.is_simple(lines) | shapely.is_closed(lines)
    flags[:, column["SHARP TURNS"]] = _sharp_turns(trace_map, turn)
    tree = shapely.STRtree(lines)
    xy, a, b, overlapping = _pair_intersections(tree, lines)
    flags[overlapping.reshape(-1), column["STACKED TRACES"]] = True
    pair_id = a * n + b
    unique, count = np.unique(pair_id, return_counts=True)
    crosscut = unique[count > 2]
    flags[np.concatenate([crosscut // n, crosscut % n]), column["MULTIPLE CROSSCUTS"]] = True
    ends = _endpoints_xy(trace_map)
    node_xy, node_owner, end_xy, end_owner = _nodes(ends, xy, a, b)
    reach = SNAP_ERROR_MULTIPLIER * tau
    flags[_clustered(end_xy, end_owner, reach, 1), column["V NODE"]] = True
    flags[_clustered(node_xy, node_owner, reach, 2), column["MULTI JUNCTION"]] = True
    under, over = _snap_misses(tree, lines, ends, tau, reach)
    flags[under, column["UNDERLAPPING SNAP"]] = True
    flags[over, column["OVERLAPPING SNAP"]] = True
    return TraceValidation(flags, tau, turn)


def _sharp_turns(trace_map: TraceMap, limit_deg: float) -> np.ndarray:
    """(n_traces,) bool: a trace of three or more vertices where a segment turns more than
    ``limit_deg`` from the previous segment or from the chord, or where a segment or the chord has
    zero length (fractopo's SharpCornerValidator; a trace of two vertices has no corner).

    A turn within the rounding of the coordinates of the limit is at the limit, so not beyond it:
    fractopo's ``deg_angle > threshold_angle`` with the turn it would have in exact arithmetic. The
    coordinates of a trace whose largest is X are rounded to about eps·X (eps the float64 machine
    epsilon), which turns a segment of length L by up to about eps·X/L radians; a turn between
    segments of lengths L1 and L2 is taken as beyond the limit only if it exceeds it by more than
    :data:`_TURN_ROUNDING` · eps · X · (1/L1 + 1/L2), at least :data:`_TURN_TOLERANCE_DEG` and at
    most :data:`_TURN_TOLERANCE_MAX_DEG`. The exact 90° turns of a pixel staircase are then at the
    limit wherever the traces lie (at x ≈ 5e5 m, y ≈ 9e6 m on a UTM map they compute up to a few
    1e-6 degrees either side of 90°), and a turn more than 1e-3° from the limit gets fractopo's
    label. Subtracting a vertex of the trace first would not help: differences of nearby float64
    numbers are exact already; the rounding is in the coordinates themselves.
    """
    xy, offsets, n = trace_map.xy_m, trace_map.offsets, trace_map.n_traces
    counts = np.diff(offsets)
    vertex_owner = np.repeat(np.arange(n, dtype=np.int64), counts)
    inside = vertex_owner[1:] == vertex_owner[:-1]  # step k joins vertices k and k + 1 of one trace
    segment, owner = np.diff(xy, axis=0)[inside], vertex_owner[:-1][inside]
    chord = xy[offsets[1:] - 1] - xy[offsets[:-1]]
    length, chord_length = np.hypot(*segment.T), np.hypot(*chord.T)
    largest = np.maximum.reduceat(np.abs(xy).max(axis=1), offsets[:-1])  # X of each trace (>= 2 vertices)
    with np.errstate(invalid="ignore", divide="ignore"):  # zero lengths give NaN directions
        unit = segment / length[:, None]
        chord_unit = chord / chord_length[:, None]
        wobble = _TURN_ROUNDING * np.finfo(np.float64).eps * largest[owner] / length  # radians

    def beyond(u, v, slack):  # angle between unit vectors above the limit, or undefined (NaN)
        cross = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
        angle = np.degrees(np.arctan2(np.abs(cross), np.einsum("ij,ij->i", u, v)))  # NaN stays NaN
        tolerance = np.clip(np.degrees(slack), _TURN_TOLERANCE_DEG, _TURN_TOLERANCE_MAX_DEG)
        return ~(angle <= limit_deg + tolerance)

    with np.errstate(invalid="ignore", divide="ignore"):
        chord_wobble = _TURN_ROUNDING * np.finfo(np.float64).eps * largest / chord_length
    bad = np.zeros(n, dtype=bool)
    bad[owner[beyond(unit, chord_unit[owner], wobble + chord_wobble[owner])]] = True
    consecutive = owner[1:] == owner[:-1]
    bad[owner[1:][consecutive & beyond(unit[1:], unit[:-1], wobble[1:] + wobble[:-1])]] = True
    return bad & (counts > 2)


def _nodes(ends, xy, a, b) -> tuple[np.ndarray, ...]:
    """fractopo's nodes (``determine_general_nodes``): the crossing points of each trace, and the
    trace ends that are not on one of their own trace's crossing points (:data:`_ON_CROSSING`). At
    an end that touches another trace's end (:data:`_ENDS_TOUCH`), the trace's crossing points are
    dropped, so that end stays an end node and a V node can be found there.

    Returns (node_xy, node_owner, end_xy, end_owner): every node, and the end nodes alone.
    """
    n = ends.shape[0]
    end_xy = ends.reshape(-1, 2)
    end_owner = np.repeat(np.arange(n, dtype=np.int64), 2)
    points = shapely.points(end_xy)
    i, j = shapely.STRtree(points).query(points, predicate="dwithin", distance=_ENDS_TOUCH)
    touching = np.zeros(end_xy.shape[0], dtype=bool)
    touching[i[end_owner[i] != end_owner[j]]] = True
    crossing_xy, crossing_owner = np.concatenate([xy, xy]), np.concatenate([a, b])
    dropped = np.zeros(crossing_owner.size, dtype=bool)
    for k in (0, 1):
        own_end = 2 * crossing_owner + k
        dropped |= touching[own_end] & (np.hypot(*(end_xy[own_end] - crossing_xy).T) <= _ON_CROSSING)
    crossing_xy, crossing_owner = crossing_xy[~dropped], crossing_owner[~dropped]
    on_crossing = np.zeros(end_xy.shape[0], dtype=bool)
    if crossing_xy.shape[0]:
        end_index, cross_index = shapely.STRtree(shapely.points(crossing_xy)).query(
            points, predicate="dwithin", distance=_ON_CROSSING)
        mine = crossing_owner[cross_index] == end_owner[end_index]
        on_crossing[end_index[mine]] = True
    end_xy, end_owner = end_xy[~on_crossing], end_owner[~on_crossing]
    return (np.concatenate([crossing_xy, end_xy]), np.concatenate([crossing_owner, end_owner]), end_xy, end_owner)


def _clustered(xy: np.ndarray, owner: np.ndarray, reach: float, at_least: int) -> np.ndarray:
    """Traces owning a node within ``reach`` of at least ``at_least`` nodes of other traces, and the
    owners of those nodes (fractopo's ``determine_node_junctions``)."""
    if xy.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    points = shapely.points(xy)
    i, j = shapely.STRtree(points).query(points, predicate="dwithin", distance=reach)
    other = owner[i] != owner[j]
    i, j = i[other], j[other]
    crowded = np.bincount(i, minlength=xy.shape[0]) >= at_least
    hit = crowded[i]
    return np.unique(np.concatenate([owner[crowded], owner[j[hit]]]))


def _snap_misses(tree, lines, ends, tau, reach) -> tuple[np.ndarray, np.ndarray]:
    """Traces with an end in (τ, 1.1 τ] of another trace and within τ of none: (underlapping,
    overlapping), by whether the trace crosses that other trace."""
    n = ends.shape[0]
    points = shapely.points(ends.reshape(-1, 2))
    owner = np.repeat(np.arange(n, dtype=np.int64), 2)
    end_index, other = tree.query(points, predicate="dwithin", distance=reach)
    keep = other != owner[end_index]
    end_index, other = end_index[keep], other[keep]
    distance = shapely.distance(points[end_index], lines[other])
    snapped = np.zeros(points.size, dtype=bool)
    snapped[end_index[distance <= tau]] = True
    miss = ~snapped[end_index] & (distance > tau)
    end_index, other = end_index[miss], other[miss]
    crosses = shapely.intersects(lines[owner[end_index]], lines[other])
    return np.unique(owner[end_index[~crosses]]), np.unique(owner[end_index[crosses]])
