"""Join trace pieces that continue one another: across gaps and through junctions.

A skeleton breaks one joint trace into several pieces in two ways that the graph steps of
:mod:`rockmass.imaging.skeleton_graph` cannot always undo:

- a *gap* (a hidden stretch, dirt, a rock bridge) longer than the graph's bridging distance, or with
  an end that is not free because a short spur or another trace touches it;
- a *crossing* the skeleton turned into two Y nodes too far apart to be merged into an X (two lines
  crossing at a low angle, or thick ones): one line runs through both nodes and the other stops at
  each of them, so the crossing line comes back as two traces that end on the first.

:func:`link_traces` works on the chained traces (pixel polylines), whatever their ends touch: it
pairs two ends of different traces when the pieces point at each other (direction continuity),
lie on one line (small lateral offset) and are close, and joins each pair with a straight step.
Greedy by cost, each end used once, never closing a loop. This is the trace-level counterpart of
perceptual grouping by good continuation in line-segment linking [1]_.

References
----------
.. [1] Lowe, D. G. (1987). Three-dimensional object recognition from single two-dimensional
   images. Artificial Intelligence 31(3), 355-395 (grouping of segments by collinearity and
   proximity). :DOI:`10.1016/0004-3702(87)90070-1`
"""

from __future__ import annotations

import numpy as np

from .skeleton_graph import _direction, chain_end_directions

__all__ = ["link_traces", "extend_to_border", "polyline_length_px"]


def polyline_length_px(line: np.ndarray) -> float:
    """Length of a (k, 2) polyline, pixels."""
    return float(np.hypot(*np.diff(line, axis=0).T).sum()) if line.shape[0] > 1 else 0.0


def _point_at(chain: np.ndarray, arc_px: float) -> np.ndarray:
    """The vertex of ``chain`` at (just past) arc length ``arc_px`` from its first vertex."""
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(chain, axis=0).T))])
    return chain[min(int(np.searchsorted(arc, min(arc_px, arc[-1]))), chain.shape[0] - 1)]


def _check_non_negative(value, name: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return value


def _check_angle(value, name: str) -> float:
    value = float(value)
    if not (0 <= value <= 90):
        raise ValueError(f"{name} must be an angle in 0-90 degrees, got {value!r}")
    return value


def link_traces(polylines_rc_px, *, max_gap_px: float, max_turn_deg: float = 15.0,
                max_offset_px: float = 3.0, max_overlap_px: float = 3.0, skip_px: float = 3.0,
                reach_px: float = 15.0) -> list[np.ndarray]:
    r"""Join traces whose ends continue one another across a gap or through a junction.

    Parameters
    ----------
    polylines_rc_px : sequence of (k, 2) array_like
        Trace polylines, pixel (row, col), k >= 2 (shorter ones are passed through untouched).
    max_gap_px : float
        Longest end-to-end distance joined, pixels (>= 0; 0 joins only coincident ends).
    max_turn_deg : float, default 15.0
        The two end tangents must be anti-parallel within this angle: the path along one piece and
        on along the other turns by at most ``max_turn_deg``.
    max_offset_px : float, default 3.0
        Lateral offset allowed between the two pieces' lines, pixels: each anchor point (see
        ``skip_px``) lies within this distance of the other piece's tangent line.
    max_overlap_px : float, default 3.0
        How far the two ends may overlap along the line (a skeleton end bent into a junction can
        pass the other end by about the joint width), pixels.
    skip_px, reach_px : float, default 3.0, 15.0
        End tangents are measured between these arc lengths from each end (the first pixels of a
        skeleton end bend towards a junction); the anchor point is the vertex at ``skip_px``.

    Returns
    -------
    list of (m, 2) float64 ndarray
        The traces after joining; a joined trace runs along the first piece, steps straight across
        to the second and runs along it. Unjoined traces are returned unchanged, in input order,
        followed by the joined ones.

    Notes
    -----
    For end a at point :math:`p_a` with outward unit tangent :math:`u_a` and anchor :math:`q_a`
    (likewise b), a pair is a candidate when :math:`\lVert p_b - p_a\rVert \le d_{max}`,

    .. math::
        \arccos(-u_a \cdot u_b) \le \theta_{max}, \qquad
        (p_b - p_a)\cdot u_a \ge -o_{max}, \quad (p_a - p_b)\cdot u_b \ge -o_{max},

    and the perpendicular distances of :math:`q_b` from the line :math:`(q_a, u_a)` and of
    :math:`q_a` from :math:`(q_b, u_b)` are at most the offset limit. Candidates are accepted
    greedily by cost :math:`(d + 1)(1 + \theta/\theta_{max} + e/e_{max})` (d the end distance,
    θ the turn, e the larger offset), each end once, and only when the two ends belong to
    different chains so far (union-find), so no closed loop is made.

    Examples
    --------
    >>> pieces = [np.array([[10.0, 0.0], [10.0, 40.0]]), np.array([[10.0, 52.0], [10.0, 90.0]])]
    >>> [line.shape[0] for line in link_traces(pieces, max_gap_px=20.0)]
    [4]
    """
    max_gap_px = _check_non_negative(max_gap_px, "max_gap_px")
    max_offset_px = _check_non_negative(max_offset_px, "max_offset_px")
    max_overlap_px = _check_non_negative(max_overlap_px, "max_overlap_px")
    skip_px = _check_non_negative(skip_px, "skip_px")
    reach_px = _check_non_negative(reach_px, "reach_px")
    max_turn_deg = _check_angle(max_turn_deg, "max_turn_deg")
    lines = [np.asarray(p, dtype=np.float64) for p in polylines_rc_px]
    usable = [i for i, p in enumerate(lines) if p.ndim == 2 and p.shape[0] >= 2]
    if len(usable) < 2:
        return [p.copy() for p in lines]
    from scipy.spatial import cKDTree

    # end e = 2 * k + side of usable line k: side 0 at its first vertex, 1 at its last
    points = np.empty((2 * len(usable), 2))
    outward = np.empty((2 * len(usable), 2))
    anchor = np.empty((2 * len(usable), 2))
    directions = chain_end_directions([lines[i] for i in usable], skip_px=skip_px, reach_px=reach_px)
    for k, i in enumerate(usable):
        for side, chain in ((0, lines[i]), (1, lines[i][::-1])):
            points[2 * k + side] = chain[0]
            outward[2 * k + side] = -directions[k, side]
            anchor[2 * k + side] = _point_at(chain, min(skip_px, 0.5 * polyline_length_px(chain)))
    cos_turn = np.cos(np.radians(max_turn_deg))
    candidates = []
    for a, b in cKDTree(points).query_pairs(max_gap_px + 1e-9):
        if a // 2 == b // 2:
            continue
        ua, ub = outward[a], outward[b]
        if not (ua.any() and ub.any()):
            continue
        alignment = -float(np.dot(ua, ub))
        if alignment < cos_turn:
            continue
        gap = points[b] - points[a]
        if float(np.dot(gap, ua)) < -max_overlap_px or float(np.dot(-gap, ub)) < -max_overlap_px:
            continue
        qa_qb = anchor[b] - anchor[a]
        offset = max(abs(float(ua[0] * qa_qb[1] - ua[1] * qa_qb[0])),
                     abs(float(ub[0] * qa_qb[1] - ub[1] * qa_qb[0])))
        if offset > max_offset_px:
            continue
        turn = float(np.degrees(np.arccos(min(alignment, 1.0))))
        cost = (float(np.hypot(*gap)) + 1.0) * (1.0 + turn / max(max_turn_deg, 1e-9)
                                                + offset / max(max_offset_px, 1e-9))
        candidates.append((cost, a, b))
    parent = list(range(len(usable)))

    def root(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    partner: dict[int, int] = {}
    for _, a, b in sorted(candidates):
        if a in partner or b in partner:
            continue
        ra, rb = root(a // 2), root(b // 2)
        if ra == rb:
            continue
        parent[ra] = rb
        partner[a], partner[b] = b, a
    if not partner:
        return [p.copy() for p in lines]
    joined_lines = set()
    out = []
    for k in range(len(usable)):
        for start_side in (0, 1):
            if 2 * k + start_side in partner or k in joined_lines:
                continue
            if 2 * k + 1 - start_side not in partner:
                continue
            pieces, end = [], 2 * k + start_side
            while True:  # walk the chain from its free end
                line_k, side = end // 2, end % 2
                joined_lines.add(line_k)
                chain = lines[usable[line_k]]
                pieces.append(chain if side == 0 else chain[::-1])
                far = 2 * line_k + 1 - side
                if far not in partner:
                    break
                end = partner[far]
            out.append(np.vstack(pieces))
    joined = {usable[k] for k in joined_lines}
    unjoined = [lines[i].copy() for i in range(len(lines)) if i not in joined]
    return unjoined + out


def extend_to_border(polylines_rc_px, shape_px, *, max_distance_px: float, max_angle_deg: float = 45.0,
                     skip_px: float = 3.0, reach_px: float = 15.0) -> list[np.ndarray]:
    r"""Extend trace ends that stop just short of the image border out to it.

    Ridge filters lose response within a filter width of the border, and a skeleton shortens each
    line end by about half the line width (docs/imaging.md §7), so a trace that leaves the image ends a
    few pixels inside it: it would count as an isolated (I) end instead of a window-edge (E) end, and
    its clipped length would be short.

    Parameters
    ----------
    polylines_rc_px : sequence of (k, 2) array_like
        Trace polylines, pixel (row, col) on an image of ``shape_px``.
    shape_px : (rows, cols)
        The image; its border runs along pixel edges, rows -0.5 and rows - 0.5 (likewise columns).
    max_distance_px : float
        An end is extended when the border lies at most this far along its outward tangent, pixels.
    max_angle_deg : float, default 45.0
        ... and the tangent meets the border within this angle of the border's normal (a trace
        running along the border is left alone).
    skip_px, reach_px : float, default 3.0, 15.0
        Where end tangents are measured (as in :func:`link_traces`).

    Returns
    -------
    list of (m, 2) float64 ndarray
        One new vertex on the border appended at each extended end; others unchanged.

    Notes
    -----
    The border distance along a unit tangent :math:`u` from :math:`p` is the smallest positive
    :math:`t` with :math:`p + t u` on one of the four border lines (a ray-box exit distance).

    Examples
    --------
    >>> line = np.array([[50.0, 6.0], [50.0, 80.0]])
    >>> extend_to_border([line], (100, 100), max_distance_px=10.0)[0][0].tolist()
    [50.0, -0.5]
    """
    max_distance_px = _check_non_negative(max_distance_px, "max_distance_px")
    skip_px = _check_non_negative(skip_px, "skip_px")
    reach_px = _check_non_negative(reach_px, "reach_px")
    max_angle_deg = _check_angle(max_angle_deg, "max_angle_deg")
    h, w = (int(v) for v in shape_px)
    low, high = np.array([-0.5, -0.5]), np.array([h - 0.5, w - 0.5])
    cos_limit = np.cos(np.radians(max_angle_deg))
    out = []
    for line in polylines_rc_px:
        line = np.asarray(line, dtype=np.float64)
        if line.ndim != 2 or line.shape[0] < 2:
            out.append(line.copy())
            continue
        pieces = [line]
        for side in (0, 1):
            chain = pieces[-1] if side == 0 else pieces[-1][::-1]
            p, u = chain[0], -_direction(chain, skip_px, reach_px)
            axes = [k for k in (0, 1) if abs(u[k]) > 1e-12]
            if not axes:
                continue
            exits = [((high[k] if u[k] > 0 else low[k]) - p[k]) / u[k] for k in axes]
            first = int(np.argmin(exits))
            t = exits[first]
            if not (0 < t <= max_distance_px) or abs(u[axes[first]]) < cos_limit:
                continue
            tip = np.clip(p + t * u, low, high)
            chain = np.vstack([tip, chain])
            pieces[-1] = chain if side == 0 else chain[::-1]
        out.append(pieces[-1])
    return out
