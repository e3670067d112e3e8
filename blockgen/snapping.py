"""Collapse block edges shorter than the solver's minimum edge ``2d`` (docs/blocks.md §6).

A DEM with corner rounding ``d`` cannot hold an edge shorter than ``2d``: both rounded corners would
overlap. Such edges come from joints or cracks meeting close to another line. They are collapsed
one at a time by moving their two end nodes onto one point, in every block that uses either node
(the network is one set of shared nodes, so both neighbouring blocks change together).

Rule for one edge ``(u, v)`` of length < ``min_edge_m`` (shortest first):

1. **Which node may move.** A node on the domain boundary or on an excavation outline is *pinned*
   to that outline: it may only be the target, or move along a straight piece of it (a node where
   the outline turns is a corner and never moves). Candidate targets, in order: the midpoint (when
   neither end is pinned), ``u``, ``v``.
2. **Accepted** when, for every block touching ``u`` or ``v``: the new ring is convex (no reflex
   vertex beyond ``reflex_sin`` and ``reflex_m``) with positive area, or has collapsed to nothing
   (a triangle on the edge, its area passing to its neighbours) — but not thinner than half the
   minimum edge in mean width 2·area/perimeter and less than half as wide as it was (a nearly
   collinear triangle would drive the DEM time step to nothing); and the area of these blocks,
   summed per region, is unchanged (to 1e-12 relative) — so the domain and every excavation stage
   keep their areas exactly, and no block overlaps another. Otherwise the next candidate is tried;
   an edge with no acceptable candidate is left and listed. The midpoint is rounded to the noding
   grid (every node lies on it).
3. Blocks changed by an accepted collapse wait for the next pass (their geometry changed); passes
   repeat until nothing changes. The blocks are rebuilt locally from their new rings (no new
   polygonisation); the builder then re-checks convexity.

Every collapse is reported (``quality.edges_snapped``): the edge length, both old nodes, the new
point, the blocks involved and the kinds of the lines that moved. Lines keep their labels: a joint
edge that moved is still that joint's edge.
"""

from __future__ import annotations

import numpy as np

from ..dfn.polygon import signed_area
from .convex import reflex_vertices
from .model import KIND_DOMAIN, KIND_EXCAVATION
from .network import exterior_coords, unique_rows

__all__ = ["snap_short_edges", "AREA_RTOL"]

#: relative change of the area of the touched blocks (per region) accepted as none.
AREA_RTOL = 1e-12


def snap_short_edges(noded, kind, src, faces, region, min_edge_m, grid_m, reflex_sin,
                     reflex_m=0.0, max_passes=8):
    """Collapse every block edge shorter than ``min_edge_m`` that the rule allows.

    The blocks are updated in place of a new polygonisation: only the blocks around a collapsed
    edge change, and their new rings are known (a local rebuild).

    Parameters
    ----------
    noded : (n, 2, 2) float64
        The noded network (2-point segments; node coordinates on the ``grid_m``).
    kind, src : (n,) int64
        Labels of the segments.
    faces : array of shapely Polygons
        The blocks (counter-clockwise, polygonised from ``noded``).
    region : (n_faces,) int64
    min_edge_m, grid_m, reflex_sin, reflex_m : float
        Tolerances (:mod:`rockmass.blockgen.tolerances`).

    Returns
    -------
    noded, kind, src, faces, region
        After the collapses; segments keep their labels (two that now coincide keep the label of
        the lower kind index).
    moved : (n,) bool
        Segments of the returned network that moved.
    changes : list of dict
        One entry per collapse.
    left : int
        Block edges still shorter than ``min_edge_m`` (no acceptable collapse).
    """
    changes: list[dict] = []
    moved = np.zeros(len(noded), bool)
    left = 0
    faces = np.array(faces, dtype=object)
    region = np.asarray(region)
    for _ in range(max_passes):
        out = _one_pass(noded, kind, src, moved, faces, region, min_edge_m, grid_m, reflex_sin,
                        reflex_m, changes)
        if out is None:
            break
        noded, kind, src, moved, faces, region, n_new, left = out
        if not n_new:
            break
    return noded, kind, src, faces, region, moved, changes, left


def _hash(q):
    """An int64 hash of integer grid coordinates (n, 2), exact matches checked by the caller."""
    return q[:, 0] * np.int64(0x9E3779B1) ^ q[:, 1]


def _one_pass(noded, kind, src, moved, faces, region, min_edge_m, grid_m, reflex_sin, reflex_m,
              changes):
    import shapely

    coords, index = exterior_coords(faces)
    counts = np.bincount(index, minlength=len(faces))
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    is_last = np.zeros(len(coords), bool)
    is_last[start + counts - 1] = True
    e_from = np.flatnonzero(~is_last)
    e_len = np.hypot(*(coords[e_from + 1] - coords[e_from]).T)
    tiny = e_from[e_len < min_edge_m]
    if not len(tiny):
        return None
    # the nodes of the short edges, matched exactly on the grid in the rings and the network
    qr = np.round(coords / grid_m).astype(np.int64)
    ends = unique_rows(np.concatenate([qr[tiny], qr[tiny + 1]]))[0]
    node_id = {tuple(k): i for i, k in enumerate(ends.tolist())}
    xy = ends * grid_m  # on the grid, as every network node
    h_ends = _hash(ends)

    def ids_of(q):
        out = np.full(len(q), -1, np.int64)
        for i in np.flatnonzero(np.isin(_hash(q), h_ends)).tolist():
            out[i] = node_id.get((int(q[i, 0]), int(q[i, 1])), -1)
        return out

    ring_id = ids_of(qr)
    qn = np.round(noded.reshape(-1, 2) / grid_m).astype(np.int64)
    seg_id = ids_of(qn).reshape(-1, 2)
    faces_of: dict[int, set[int]] = {}
    near = (ring_id >= 0) & ~is_last
    for n, f in zip(ring_id[near].tolist(), index[near].tolist()):
        faces_of.setdefault(n, set()).add(f)
    # pinned nodes: on the domain boundary or an excavation outline, with their outline directions
    pinned_dirs: dict[int, list[np.ndarray]] = {}
    outline = (kind == KIND_DOMAIN) | (kind == KIND_EXCAVATION)
    for s in np.flatnonzero(outline & (seg_id >= 0).any(axis=1)).tolist():
        d = noded[s, 1] - noded[s, 0]
        d = d / np.hypot(*d)
        for n in seg_id[s]:
            if n >= 0:
                pinned_dirs.setdefault(int(n), []).append(d)

    # the network segments at each node of a short edge (CSR by node id), for the report
    flat = seg_id.ravel()
    at_node = np.flatnonzero(flat >= 0)
    by_node = at_node[np.argsort(flat[at_node], kind="stable")] // 2
    seg_ptr = np.concatenate([[0], np.cumsum(np.bincount(flat[at_node], minlength=len(ends)))])

    def corner(n):
        dirs = pinned_dirs[n]
        return len(dirs) < 2 or any(abs(dirs[0][0] * d[1] - dirs[0][1] * d[0]) > reflex_sin
                                    for d in dirs[1:])

    def ring(f):
        sl = slice(start[f], start[f] + counts[f] - 1)
        return coords[sl], ring_id[sl]

    cand = {}
    for i in tiny.tolist():
        a, b = int(ring_id[i]), int(ring_id[i + 1])
        key = (min(a, b), max(a, b))
        if a != b and key not in cand:
            cand[key] = float(np.hypot(*(xy[b] - xy[a])))
    busy: set[int] = set()
    moves: dict[int, np.ndarray] = {}
    new_faces: dict[int, np.ndarray | None] = {}
    n_new = left = 0
    for (u, v), length in sorted(cand.items(), key=lambda kv: kv[1]):
        touched = sorted(faces_of.get(u, set()) | faces_of.get(v, set()))
        if busy.intersection(touched) or u in moves or v in moves:
            left += 1
            continue
        pu, pv = u in pinned_dirs, v in pinned_dirs
        targets = []
        if not pu and not pv:
            targets.append(np.round(0.5 * (xy[u] + xy[v]) / grid_m) * grid_m)
        if not pv or (pu and not corner(v) and _collinear_on_outline(u, v, xy, pinned_dirs, reflex_sin)):
            targets.append(xy[u])  # v moves onto u
        if not pu or (pv and not corner(u) and _collinear_on_outline(v, u, xy, pinned_dirs, reflex_sin)):
            targets.append(xy[v])  # u moves onto v
        for p in targets:
            rings = _try(p, u, v, [ring(f) for f in touched], [int(region[f]) for f in touched],
                         reflex_sin, reflex_m, 0.5 * min_edge_m)
            if rings is not None:
                moves[u] = moves[v] = p
                busy.update(touched)
                new_faces.update(zip(touched, rings))
                segs = np.concatenate([by_node[seg_ptr[u]:seg_ptr[u + 1]],
                                       by_node[seg_ptr[v]:seg_ptr[v + 1]]])
                changes.append({"edge_m": length, "from_xy_m": [xy[u].tolist(), xy[v].tolist()],
                                "to_xy_m": [float(p[0]), float(p[1])], "n_blocks": len(touched),
                                "n_blocks_removed": sum(r is None for r in rings),
                                "moved_kinds": sorted({int(k) for k in kind[segs].tolist()})})
                n_new += 1
                break
        else:
            left += 1
    if not moves:
        return noded, kind, src, moved, faces, region, 0, left
    # the network: every segment end on a moved node goes to its new point
    out = noded.copy()
    target = np.zeros((len(ends), 2))
    is_moved = np.zeros(len(ends) + 1, bool)  # index -1 -> last entry, never moved
    for n, p in moves.items():
        target[n] = p
        is_moved[n] = True
    hit = is_moved[seg_id]
    out[hit] = target[seg_id[hit]]
    moved = moved | hit.any(axis=1)
    keep = np.any(out[:, 0] != out[:, 1], axis=1)
    out, kind, src, moved = out[keep], kind[keep], src[keep], moved[keep]
    # two moved segments that now join the same nodes are one: the lower kind index keeps its label
    sel = np.flatnonzero(moved)
    qk = np.round(out[sel] / grid_m).astype(np.int64).reshape(-1, 4)
    swap = (qk[:, 0] > qk[:, 2]) | ((qk[:, 0] == qk[:, 2]) & (qk[:, 1] > qk[:, 3]))
    key = np.where(swap[:, None], qk[:, [2, 3, 0, 1]], qk)
    order = np.lexsort((src[sel], kind[sel], key[:, 3], key[:, 2], key[:, 1], key[:, 0]))
    dup = np.zeros(len(sel), bool)
    dup[1:] = np.all(key[order][1:] == key[order][:-1], axis=1)
    drop = np.zeros(len(out), bool)
    drop[sel[order][dup]] = True
    out, kind, src, moved = out[~drop], kind[~drop], src[~drop], moved[~drop]
    # the blocks: local rebuild of the touched ones, vanished ones removed
    faces = faces.copy()
    gone = []
    for f, ring_xy in new_faces.items():
        if ring_xy is None:
            gone.append(f)
        else:
            faces[f] = shapely.Polygon(ring_xy)
    if gone:
        faces = np.delete(faces, gone)
        region = np.delete(region, gone)
    return out, kind, src, moved, faces, region, n_new, left


def _collinear_on_outline(target, mover, xy, pinned_dirs, reflex_sin):
    """The pinned ``mover`` may slide onto ``target`` only along its own straight outline."""
    d = xy[target] - xy[mover]
    d = d / np.hypot(*d)
    return all(abs(d[0] * e[1] - d[1] * e[0]) <= reflex_sin for e in pinned_dirs[mover])


def _mean_width(xy):
    """2·area / perimeter of a ring (the sliver measure of :mod:`rockmass.blockgen.builder`)."""
    perimeter = float(np.sum(np.hypot(*(np.concatenate([xy[1:], xy[:1]]) - xy).T)))
    return 2.0 * abs(signed_area(xy)) / perimeter if perimeter > 0 else 0.0


def _try(p, u, v, rings, regions, reflex_sin, reflex_m, min_width=0.0):
    """New rings (None: the block vanishes) of the blocks ``rings`` = [(coords, node ids)] if u and
    v go to ``p``; None if the rule refuses the move (including a block that would end thinner
    than ``min_width`` in mean width 2·area/perimeter and less than half as wide as before: a
    nearly collinear triangle left by a collapse would drive the DEM time step to nothing)."""
    before: dict[int, float] = {}
    after: dict[int, float] = {}
    out = []
    for (ring_xy, ids), reg in zip(rings, regions):
        before[reg] = before.get(reg, 0.0) + signed_area(ring_xy)
        merged = (ids == u) | (ids == v)
        # one vertex for u, v adjacent (cyclic; the previous flag by concatenation, not np.roll,
        # which costs several times more on a small ring)
        keep = ~(merged & np.concatenate([merged[-1:], merged[:-1]]))
        if int((merged & keep).sum()) > 1:
            return None  # u and v both on this block but not as one edge: it would be pinched
        if keep.sum() < 3:
            out.append(None)  # a triangle on the edge: its area passes to its neighbours
            continue
        new_xy = ring_xy.copy()
        new_xy[merged] = p
        new_xy = new_xy[keep]
        area = signed_area(new_xy)
        if area <= 0 or len(reflex_vertices(new_xy, reflex_sin, reflex_m)):
            return None
        width = _mean_width(new_xy)
        if width < min_width and width < 0.5 * _mean_width(ring_xy):
            return None
        after[reg] = after.get(reg, 0.0) + area
        out.append(new_xy)
    total = sum(abs(a) for a in before.values())
    for reg in set(before) | set(after):
        if abs(before.get(reg, 0.0) - after.get(reg, 0.0)) > AREA_RTOL * total:
            return None
    return out
