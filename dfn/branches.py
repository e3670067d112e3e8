"""Branches and nodes of a trace network, as fractopo's ``branches`` and ``nodes`` layers.

A *branch* is a piece of a trace between two consecutive nodes (Sanderson & Nixon 2015). The nodes
are those of :func:`~rockmass.dfn.topology.trace_topology` (snap tolerance τ): X nodes where two
traces cross, Y nodes where a trace end abuts another trace, I nodes at isolated ends, and E nodes
where the window (the mapped area) censors a trace. :func:`branches_and_nodes` cuts every trace at

- its X nodes and the points where other traces abut it (their Y ends, projected onto it),
- the points where it crosses the window boundary (E nodes, as fractopo clips traces to the area),
- its own two ends,

keeps the pieces inside the window (a piece is kept when its middle point is in the window, edge
included), and drops pieces shorter than τ (fractopo drops branches shorter than its snap threshold).
Cut points closer than τ along a trace are one node; its class is C (X or Y) over E over I.

Each branch is named by its two ends as fractopo does (``fractopo.general``): an X or Y end is C
("connected"), so a branch is ``"C - C"``, ``"C - I"``, ``"C - E"``, ``"I - I"``, ``"I - E"`` or
``"E - E"`` (C before I before E). Nodes carry fractopo's ``Class``: ``"X"``, ``"Y"``, ``"I"``, ``"E"``.

Node counts are the topology's (``TraceTopology.n_x``, ``n_y``, ``n_i``); the E nodes of the layer
are the branch ends on the window boundary, one per boundary crossing, which equals the topology's
count of E ends unless a trace leaves and re-enters the window (each crossing is then a node here).

References
----------
.. [1] Sanderson, D. J., Nixon, C. W. (2015). The use of topology in fracture network
   characterization. J. Struct. Geol. 72, 55-66.
.. [2] Ovaskainen, N., Nordbäck, N., Skyttä, P., Engström, J. (2022). A new subsampling methodology
   to optimize the characterization of two-dimensional bedrock fracture networks (fractopo).
   J. Struct. Geol. 155, 104528.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from .intensity import _endpoints_xy, _optional_window
from .topology import trace_topology
from .tracemap import TraceMap, _require_trace_map

__all__ = ["BranchesAndNodes", "branches_and_nodes"]  # constants: import them by module

#: fractopo's node classes (``Class`` field) and branch classes (``Connection`` field).
NODE_CLASSES = ("X", "Y", "I", "E")
BRANCH_CLASSES = ("C - C", "C - I", "C - E", "I - I", "I - E", "E - E")

_END_LETTERS = "CIE"  # order of a branch's two ends in its name (fractopo: "C - I", "I - E")
_PRIORITY = {"I": 0, "E": 1, "C": 2}  # coinciding cut points: C over E over I


@dataclass(frozen=True)
class BranchesAndNodes:
    """The branches and nodes of a trace network (structure of arrays).

    Attributes
    ----------
    nodes_xy_m : (n_nodes, 2) float64
        Node positions (x, y) in metres.
    node_class : (n_nodes,) str
        ``"X"``, ``"Y"``, ``"I"`` or ``"E"`` (fractopo's ``Class``).
    branch_xy_m : (n_vertices, 2) float64
        Branch vertices; branch k is ``branch_xy_m[branch_offsets[k]:branch_offsets[k + 1]]``.
    branch_offsets : (n_branches + 1,) int64
        Ragged offsets into ``branch_xy_m``.
    branch_trace : (n_branches,) int64
        Index of the trace each branch is a piece of.
    connection : (n_branches,) str
        ``"C - C"``, ``"C - I"``, ... (fractopo's ``Connection``).
    snap_tolerance_m : float
        The tolerance τ of the topology.
    """

    nodes_xy_m: np.ndarray
    node_class: np.ndarray
    branch_xy_m: np.ndarray
    branch_offsets: np.ndarray
    branch_trace: np.ndarray
    connection: np.ndarray
    snap_tolerance_m: float

    @property
    def n_branches(self) -> int:
        """Number of branches."""
        return int(self.branch_trace.size)

    def branch_lines(self) -> np.ndarray:
        """The branches as an array of shapely LineStrings."""
        if self.n_branches == 0:
            return np.zeros(0, dtype=object)
        return shapely.from_ragged_array(shapely.GeometryType.LINESTRING, self.branch_xy_m, (self.branch_offsets,))

    def branch_lengths_m(self) -> np.ndarray:
        """(n_branches,) float64 length of each branch in metres."""
        return shapely.length(self.branch_lines()).astype(np.float64)

    def node_counts(self) -> dict[str, int]:
        """``{"X", "Y", "I", "E"}``: nodes of each class."""
        counts = Counter(self.node_class.tolist())
        return {c: int(counts.get(c, 0)) for c in NODE_CLASSES}

    def branch_counts(self) -> dict[str, int]:
        """Branches of each class, keyed as :data:`BRANCH_CLASSES`."""
        counts = Counter(self.connection.tolist())
        return {c: int(counts.get(c, 0)) for c in BRANCH_CLASSES}


def branches_and_nodes(trace_map: TraceMap, *, snap_tolerance_m: float, window: Any = None) -> BranchesAndNodes:
    """Cut traces into branches at their nodes, and list the nodes with fractopo's classes.

    Parameters
    ----------
    trace_map : TraceMap
        The traces.
    snap_tolerance_m : float
        Snap tolerance τ >= 0 in metres, as for :func:`~rockmass.dfn.topology.trace_topology`.
    window : array_like, shapely.Polygon or SamplingWindow, optional
        The sampling window; default None: the map's own, else none (no E nodes, nothing clipped).

    Returns
    -------
    BranchesAndNodes

    Notes
    -----
    The cutting rules are in the module docstring. A trace that touches itself is cut where
    :func:`shapely.line_locate_point` places each node (its first passage).

    Examples
    --------
    A "+" of two traces and a third abutting the vertical one, in a 10 m square: one X, one Y,
    five I nodes; the horizontal trace has two branches, the vertical three, the abutting one one.

    >>> tm = TraceMap.from_segments([[2, 5, 8, 5], [5, 2, 5, 8], [5, 7, 7, 7]],
    ...                             window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    >>> net = branches_and_nodes(tm, snap_tolerance_m=0.001)
    >>> net.node_counts(), net.branch_counts()["C - I"], net.branch_counts()["C - C"]
    ({'X': 1, 'Y': 1, 'I': 5, 'E': 0}, 5, 1)
    """
    _require_trace_map(trace_map)
    topology = trace_topology(trace_map, snap_tolerance_m=snap_tolerance_m, window=window)
    resolved = _optional_window(trace_map, window)
    tau = topology.snap_tolerance_m
    lines = trace_map.to_shapely()
    trace, s, letter, at_end = _cut_points(trace_map, lines, topology, resolved)
    group_trace, group_s, group_letter = _merge_cut_points(trace, s, letter, at_end, tau)
    first = np.flatnonzero((group_trace[:-1] == group_trace[1:]) & (np.diff(group_s) > tau))
    if resolved is not None and first.size:
        middle = shapely.line_interpolate_point(lines[group_trace[first]], 0.5 * (group_s[first] + group_s[first + 1]))
        first = first[shapely.intersects(resolved.polygon, middle)]
    pieces = [_cut(trace_map.polyline(t), a, b) for t, a, b in zip(group_trace[first], group_s[first], group_s[first + 1])]
    offsets = np.zeros(len(pieces) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([p.shape[0] for p in pieces])
    ends = np.stack([group_letter[first], group_letter[first + 1]], axis=1) if first.size else np.zeros((0, 2), str)
    connection = np.array([" - ".join(sorted(pair, key=_END_LETTERS.index)) for pair in ends.tolist()], dtype="<U5")
    nodes_xy, node_class = _nodes(trace_map, topology, group_trace, group_s, group_letter, first, lines)
    return BranchesAndNodes(
        nodes_xy_m=nodes_xy,
        node_class=node_class,
        branch_xy_m=np.concatenate(pieces) if pieces else np.zeros((0, 2)),
        branch_offsets=offsets,
        branch_trace=group_trace[first].astype(np.int64),
        connection=connection,
        snap_tolerance_m=tau,
    )


def _cut_points(trace_map: TraceMap, lines: np.ndarray, topology, resolved) -> tuple[np.ndarray, ...]:
    """Every cut point as (trace, distance along it, end letter C / I / E, is the trace's last end)."""
    n = trace_map.n_traces
    ends = _endpoints_xy(trace_map)
    own = np.where(topology.end_class == "Y", "C", topology.end_class)
    traces = [np.arange(n), np.arange(n)]
    distances = [np.zeros(n), trace_map.lengths_m()]
    letters = [own[:, 0], own[:, 1]]
    last = [np.zeros(n, bool), np.ones(n, bool)]

    def add(on_trace: np.ndarray, xy: np.ndarray, letter: str) -> None:
        traces.append(on_trace)
        distances.append(shapely.line_locate_point(lines[on_trace], shapely.points(xy).reshape(-1)))
        letters.append(np.full(on_trace.size, letter))
        last.append(np.zeros(on_trace.size, bool))

    for column in (0, 1):  # each crossing cuts both traces
        add(topology.x_node_traces[:, column], topology.x_nodes_xy_m, "C")
    abutting = topology.abutted_trace.reshape(-1) >= 0
    add(topology.abutted_trace.reshape(-1)[abutting], ends.reshape(-1, 2)[abutting], "C")
    if resolved is not None and n:
        crossing = shapely.intersection(lines, resolved.boundary)
        xy, index = shapely.get_coordinates(crossing, return_index=True)
        add(index.astype(np.int64), xy, "E")
    return (np.concatenate(traces).astype(np.int64), np.concatenate(distances), np.concatenate(letters),
            np.concatenate(last))


def _merge_cut_points(trace, s, letter, at_end, tau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cut points sorted along each trace, those closer than τ merged into one (C over E over I; at
    a trace end, the end's position)."""
    order = np.lexsort((s, trace))
    trace, s, letter, at_end = trace[order], s[order], letter[order], at_end[order]
    if trace.size == 0:
        return trace, s, letter
    new = np.ones(trace.size, dtype=bool)
    new[1:] = (trace[1:] != trace[:-1]) | (np.diff(s) > tau)
    starts = np.flatnonzero(new)
    rank = np.array([_PRIORITY[c] for c in letter.tolist()], dtype=np.int64)
    best = np.maximum.reduceat(rank, starts)
    by_rank = np.array(sorted(_PRIORITY, key=_PRIORITY.get))
    position = np.minimum.reduceat(s, starts)
    ends_last = np.maximum.reduceat(np.where(at_end, s, -np.inf), starts)
    position = np.where(np.isfinite(ends_last), ends_last, position)
    return trace[starts], position, by_rank[best]


def _cut(xy: np.ndarray, s_a: float, s_b: float) -> np.ndarray:
    """The piece of the polyline ``xy`` between distances ``s_a < s_b`` along it."""
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    inner = xy[(along > s_a) & (along < s_b)]
    at = np.array([[np.interp(s, along, xy[:, 0]), np.interp(s, along, xy[:, 1])] for s in (s_a, s_b)])
    return np.concatenate([at[:1], inner, at[1:]])


def _nodes(trace_map, topology, group_trace, group_s, group_letter, first, lines) -> tuple[np.ndarray, np.ndarray]:
    """X nodes, the I and Y trace ends, and the E nodes that end a kept branch."""
    ends = _endpoints_xy(trace_map).reshape(-1, 2)
    end_class = topology.end_class.reshape(-1)
    iy = (end_class == "I") | (end_class == "Y")
    kept = np.unique(np.concatenate([first, first + 1]))
    e_groups = kept[group_letter[kept] == "E"]
    e_xy = shapely.get_coordinates(shapely.line_interpolate_point(lines[group_trace[e_groups]], group_s[e_groups]))
    xy = np.concatenate([topology.x_nodes_xy_m, ends[iy], e_xy.reshape(-1, 2)])
    classes = np.concatenate([np.full(topology.n_x, "X"), end_class[iy], np.full(e_groups.size, "E")])
    return xy, classes.astype("<U1")
