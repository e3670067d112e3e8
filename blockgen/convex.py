"""Convex decomposition of concave blocks by bisector cuts.

Rule: while a piece has a reflex vertex v (interior angle > 180°), cut it along the bisector of the
interior angle at v, from v to the first point where the bisector meets the piece's boundary. The
cut halves the reflex angle, so v is convex in both new pieces; it ends on an edge at an angle below
180° on both sides, so no new reflex vertex appears and the process stops after at most (number of
reflex vertices) cuts. Near a circular opening the bisector is the radial direction, giving the
radial wedges a DEM user would draw. If the cut ends within ``min_edge_m`` of a vertex of the piece,
it is snapped onto that vertex (no edge shorter than the solver's minimum is created), and the
snap is reported. A piece with holes is first cut by the two bisectors from the left-most and
right-most vertices of each hole, which split it into pieces without holes.
"""

from __future__ import annotations

import numpy as np
import shapely

__all__ = ["reflex_vertices", "convex_cuts", "is_reflex"]


def is_reflex(e_in: np.ndarray, e_out: np.ndarray, reflex_sin: float, reflex_m: float) -> np.ndarray:
    """Reflex test of vertices from their incoming and outgoing edges ((m, 2) each); the rule of
    :func:`reflex_vertices`."""
    cross = e_in[:, 0] * e_out[:, 1] - e_in[:, 1] * e_out[:, 0]
    norm = np.hypot(e_in[:, 0], e_in[:, 1]) * np.hypot(e_out[:, 0], e_out[:, 1])
    chord = np.hypot(*(e_in + e_out).T)
    return (cross < -reflex_sin * norm) & (-cross > reflex_m * chord)


def reflex_vertices(xy: np.ndarray, reflex_sin: float, reflex_m: float = 0.0) -> np.ndarray:
    """Indices of reflex vertices of a counter-clockwise open ring ``xy`` ((k, 2)).

    Vertex v (neighbours a, b) is reflex when it turns clockwise, ``e_in × e_out < −reflex_sin ·
    |e_in||e_out|``, and lies more than ``reflex_m`` inside the chord a→b: the height
    ``h = −(e_in × e_out) / |b − a|`` (:mod:`rockmass.blockgen.tolerances`: a collinear vertex moved
    off its line by snap-rounding is not reflex).
    """
    # np.roll's neighbours by concatenation (np.roll costs ~10 µs a call; this runs per ring)
    e_in = xy - np.concatenate([xy[-1:], xy[:-1]])
    e_out = np.concatenate([xy[1:], xy[:1]]) - xy
    return np.flatnonzero(is_reflex(e_in, e_out, reflex_sin, reflex_m))


def _bisector(xy, i, ccw_interior=True):
    p = xy[i]
    a = xy[i - 1] - p
    b = xy[(i + 1) % len(xy)] - p
    a /= np.hypot(*a)
    b /= np.hypot(*b)
    d = a + b
    if np.hypot(*d) < 1e-12:  # straight angle: perpendicular to the edge, into the interior
        d = np.array([-b[1], b[0]])
    d /= np.hypot(*d)
    # at a reflex vertex of a CCW ring the interior bisector points away from a + b
    return -d if ccw_interior else d


def _cut_from(piece, p, d, size, min_edge):
    ray = shapely.LineString([p, p + d * size])
    hits = shapely.get_coordinates(shapely.intersection(ray, piece.boundary))
    dist = np.hypot(*(hits - p).T)
    ok = dist > min_edge * 1e-6
    if not ok.any():
        return None, False
    q = hits[ok][np.argmin(dist[ok])]
    verts = shapely.get_coordinates(piece.boundary)
    dv = np.hypot(*(verts - q).T)
    dv[np.hypot(*(verts - p).T) == 0] = np.inf
    snapped = False
    k = np.argmin(dv)
    if 0 < dv[k] < min_edge:
        cand = shapely.LineString([p, verts[k]])
        if shapely.covers(piece, cand) and not shapely.covers(piece.boundary, cand):
            q, snapped = verts[k], True
    return np.array([p, q]), snapped


def _extended(cut, eps):
    d = cut[1] - cut[0]
    d = d / np.hypot(*d) * eps
    return np.array([cut[0] - d, cut[1] + d])


def _pieces(piece, cuts, eps):
    lines = shapely.union_all([piece.boundary] + [shapely.LineString(_extended(c, eps)) for c in cuts])
    parts = shapely.get_parts(shapely.polygonize(shapely.get_parts(lines)))
    return [shapely.orient_polygons(g) for g in parts
            if g.area > 0 and shapely.within(g.representative_point(), piece)]


def convex_cuts(face, reflex_sin: float, min_edge_m: float, eps_m: float, max_cuts: int = 10000,
                reflex_m: float = 0.0):
    """Cut segments that decompose polygon ``face`` into convex pieces.

    Each cut is lengthened by ``eps_m`` at both ends so that noding always meets the boundary it
    ends on (floating-point intersections may stop a hair short); the overhangs are dangles that
    polygonisation drops.

    Returns
    -------
    cuts : list of (2, 2) arrays
    n_snapped : int
        Cuts whose end was snapped onto a vertex.
    n_failed : int
        Pieces that a cut did not split (left concave; the caller reports them).
    """
    minx, miny, maxx, maxy = face.bounds
    size = 2.0 * float(np.hypot(maxx - minx, maxy - miny))
    todo = [shapely.orient_polygons(face)]
    cuts, n_snapped, failed = [], 0, []
    while todo and len(cuts) < max_cuts:
        piece = todo.pop()
        if len(piece.interiors):
            new = []
            for ring in piece.interiors:
                xy = np.asarray(ring.coords)[:-1]
                for i in (int(np.argmin(xy[:, 0])), int(np.argmax(xy[:, 0]))):
                    # interior of the piece lies outside the hole: bisector of the hole's outside
                    a = xy[i - 1] - xy[i]
                    b = xy[(i + 1) % len(xy)] - xy[i]
                    d = -(a / np.hypot(*a) + b / np.hypot(*b))
                    if np.hypot(*d) < 1e-12:
                        d = np.array([-b[1], b[0]])
                    d = d / np.hypot(*d)
                    if not shapely.covers(piece, shapely.Point(xy[i] + d * min_edge_m * 1e-3)):
                        d = -d
                    cut, snapped = _cut_from(piece, xy[i], d, size, min_edge_m)
                    if cut is not None:
                        new.append(cut)
                        n_snapped += snapped
            if not new:
                continue
            parts = _pieces(piece, new, eps_m)
            if len(parts) < 2:
                failed.append(piece)
                continue
            cuts.extend(new)
            todo.extend(parts)
            continue
        xy = np.asarray(piece.exterior.coords)[:-1]
        reflex = reflex_vertices(xy, reflex_sin, reflex_m)
        if not len(reflex):
            continue
        i = int(reflex[0])
        cut, snapped = _cut_from(piece, xy[i], _bisector(xy, i), size, min_edge_m)
        if cut is None:
            continue
        parts = _pieces(piece, [cut], eps_m)
        if len(parts) < 2 and snapped:  # the snapped cut did not split: cut without snapping
            cut, snapped = _cut_from(piece, xy[i], _bisector(xy, i), size, 0.0)
            parts = _pieces(piece, [cut], eps_m) if cut is not None else []
        if len(parts) < 2:
            failed.append(piece)
            continue
        cuts.append(cut)
        n_snapped += snapped
        todo.extend(parts)
    return [_extended(c, eps_m) for c in cuts], n_snapped, len(failed)
