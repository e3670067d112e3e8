"""The cut network: source lines, noding, labels, dangling ends and polygonisation (shapely/GEOS).

Every block edge comes from one noded network of 2-point segments, so two adjacent blocks share
exactly the same edge vertices and contacts can be matched by coordinates. Labels travel from the
source lines to the noded segments by proximity (``label_m``, :mod:`rockmass.blockgen.tolerances`),
with a priority when sources overlap (:class:`LabelPriority`): domain boundary, then excavation
outline, then joints and traces, then extensions of dangling ends, then convex-decomposition cuts,
then potential cracks.
"""

from __future__ import annotations

import enum
import math

import numpy as np
import shapely

from .model import KIND_DOMAIN, KIND_EXCAVATION, KIND_GLUED, SOURCE_CONVEX_CUT, SOURCE_CRACK

__all__ = ["Sources", "LabelPriority", "label_priority", "unique_rows", "snap_to_grid", "node",
           "collapse_short", "label_segments", "dangling_extensions", "polygonize_segments",
           "segment_keys"]


class LabelPriority(enum.IntEnum):
    """Which source labels an edge that several sources cover: the lowest value wins.

    Plain ints where arrays hold them (:class:`Sources` stores ``int64``).
    """

    DOMAIN = 0  #: the domain outline
    EXCAVATION = 1  #: an excavation stage's outline
    LINE = 2  #: a joint or a trace
    EXTENSION = 3  #: the extension of a dangling end (glued, or joint with ``dangling="joint"``)
    CONVEX_CUT = 4  #: a cut of the convex decomposition (source ``SOURCE_CONVEX_CUT``)
    CRACK = 5  #: a potential crack of the sub-block subdivision (source ``SOURCE_CRACK``)


def label_priority(kind: int, source: int) -> LabelPriority:
    """The priority of a label (``kind``, ``source``): outlines first, then joints and traces; a
    glued edge by its source (convex cut, crack, else the extension of a dangling end)."""
    if kind == KIND_DOMAIN:
        return LabelPriority.DOMAIN
    if kind == KIND_EXCAVATION:
        return LabelPriority.EXCAVATION
    if kind == KIND_GLUED:
        return {SOURCE_CONVEX_CUT: LabelPriority.CONVEX_CUT,
                SOURCE_CRACK: LabelPriority.CRACK}.get(source, LabelPriority.EXTENSION)
    return LabelPriority.LINE


class Sources:
    """Labelled source lines, kept as 2-point pieces short enough for a useful spatial index."""

    def __init__(self, piece_m: float):
        self.piece_m = piece_m
        self._segs, self._kind, self._src, self._prio = [], [], [], []

    def add(self, segments: np.ndarray, kind: int, source, priority: LabelPriority | None = None):
        """Add ``segments`` labelled (``kind``, ``source``); ``priority`` default: by kind (an
        outline's, else :attr:`LabelPriority.LINE`)."""
        segments = np.asarray(segments, float).reshape(-1, 2, 2)
        if not len(segments):
            return
        src = np.broadcast_to(np.asarray(source, np.int64), (len(segments),))
        # split long segments into pieces of at most piece_m
        length = np.hypot(*(segments[:, 1] - segments[:, 0]).T)
        k = np.maximum(1, np.ceil(length / self.piece_m).astype(np.int64))
        rep = np.repeat(np.arange(len(segments)), k)
        j = np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)
        t0, t1 = j / k[rep], (j + 1) / k[rep]
        a, b = segments[rep, 0], segments[rep, 1]
        pieces = np.stack([a + (b - a) * t0[:, None], a + (b - a) * t1[:, None]], axis=1)
        if priority is None:
            priority = (label_priority(kind, -1) if kind in (KIND_DOMAIN, KIND_EXCAVATION)
                        else LabelPriority.LINE)
        prio = int(priority)
        self._segs.append(pieces)
        self._kind.append(np.full(len(pieces), kind, np.int64))
        self._src.append(src[rep])
        self._prio.append(np.full(len(pieces), prio, np.int64))

    def arrays(self):
        return (np.concatenate(self._segs), np.concatenate(self._kind), np.concatenate(self._src),
                np.concatenate(self._prio))


def unique_rows(a: np.ndarray):
    """``np.unique(a, axis=0, return_inverse=True, return_counts=True)`` for 2-D int arrays, by a
    lexicographic sort of the columns (same rows, order and inverse; several times faster than
    numpy's structured-view sort)."""
    a = np.asarray(a)
    if not len(a):
        return a.copy(), np.empty(0, np.int64), np.empty(0, np.int64)
    order = np.lexsort(a.T[::-1])
    s = a[order]
    new = np.ones(len(a), bool)
    new[1:] = np.any(s[1:] != s[:-1], axis=1)
    group = np.cumsum(new) - 1
    inverse = np.empty(len(a), np.int64)
    inverse[order] = group
    return s[new], inverse, np.bincount(group)


def ring_segments(xy: np.ndarray) -> np.ndarray:
    return np.stack([xy, np.roll(xy, -1, axis=0)], axis=1)


def snap_to_grid(a: np.ndarray, grid: float) -> np.ndarray:
    """Round coordinates to a dyadic grid (``grid`` a power of two): values already on the grid,
    such as 0.25 or integers, are unchanged; round-off like cos(90°) = 6e-17 becomes exactly 0."""
    return np.round(np.asarray(a, float) / grid) * grid


def node(segments: np.ndarray, grid: float) -> np.ndarray:
    """Node 2-point segments and return the noded 2-point segments.

    GEOS ``unary_union`` with ``grid_size`` runs snap-rounding noding: every output vertex lies on
    the ``grid`` (a power of two, see :func:`snap_to_grid`), so two intersections closer than the
    grid become one node and no edge shorter than the grid can appear.
    """
    lines = shapely.linestrings(segments)
    merged = shapely.unary_union(lines, grid_size=grid)
    coords, index = shapely.get_coordinates(shapely.get_parts(merged), return_index=True)
    same = index[1:] == index[:-1]
    out = np.stack([coords[:-1][same], coords[1:][same]], axis=1)
    return out[np.any(out[:, 0] != out[:, 1], axis=1)]


def collapse_short(segments: np.ndarray, min_len: float, grid: float):
    """Merge the two nodes of every segment shorter than ``min_len`` into one.

    Snap-rounding keeps distinct nodes on neighbouring grid cells (an edge one cell long, whose
    direction is noise). Each cluster of nodes joined by such edges becomes its lowest-numbered
    node; the short segments vanish and duplicates are removed. Nodes move by < ``min_len`` ×
    cluster size. Returns (segments, number of nodes merged away).
    """
    length = np.hypot(*(segments[:, 1] - segments[:, 0]).T)
    short = length < min_len
    if not short.any():
        return segments, 0
    q = np.round(segments.reshape(-1, 2) / grid).astype(np.int64)
    uniq, inv, _ = unique_rows(q)
    inv = inv.reshape(-1, 2)
    xy = np.zeros((len(uniq), 2))
    xy[inv.ravel()] = segments.reshape(-1, 2)
    label = np.arange(len(uniq))
    a, b = inv[short, 0], inv[short, 1]
    while True:  # label propagation: every node takes the smallest label in its cluster
        m = np.minimum(label[a], label[b])
        new = label.copy()
        np.minimum.at(new, a, m)
        np.minimum.at(new, b, m)
        new = new[new]
        if np.array_equal(new, label):
            break
        label = new
    n_merged = int((label != np.arange(len(uniq))).sum())
    ends = label[inv]
    keep = ends[:, 0] != ends[:, 1]
    ends = np.sort(ends[keep], axis=1)
    ends = unique_rows(ends)[0]
    return xy[ends], n_merged


def segment_keys(segments: np.ndarray, grid: float) -> np.ndarray:
    """Orientation-free integer keys (4 int64) of segments whose ends lie on the noding ``grid``."""
    q = np.round(segments / grid).astype(np.int64)
    a, b = q[:, 0], q[:, 1]
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    lo = np.where(swap[:, None], b, a)
    hi = np.where(swap[:, None], a, b)
    return np.column_stack([lo, hi])


def label_segments(segments: np.ndarray, sources: Sources, label_m: float):
    """Kind and source of each noded segment: the best-priority source piece within ``label_m``
    of its midpoint. Segments no source explains get kind -1 (a bug; the caller checks)."""
    pieces, kind, src, prio = sources.arrays()
    tree = shapely.STRtree(shapely.linestrings(pieces))
    mid = shapely.points(segments.mean(axis=1))
    i, j = tree.query(mid, predicate="dwithin", distance=label_m)
    order = np.lexsort((src[j], prio[j], i))
    i, j = i[order], j[order]
    first = np.ones(len(i), bool)
    first[1:] = i[1:] != i[:-1]
    out_kind = np.full(len(segments), -1, np.int64)
    out_src = np.full(len(segments), -1, np.int64)
    out_kind[i[first]] = kind[j[first]]
    out_src[i[first]] = src[j[first]]
    return out_kind, out_src


def _crossing_distance(origins, directions, segments):
    """Distance t along each ray (origin p, unit direction d) to the line of its paired segment
    [a, b]: t = ((a − p) × e) / (d × e) with e = b − a; inf where d ∥ e (collinear or parallel)."""
    p, d = origins, directions
    a, b = segments[:, 0], segments[:, 1]
    e = b - a
    denom = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
    w = a - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / denom
    return np.where(np.abs(denom) > 0, t, np.inf)


def _mean_free_path(segments):
    """π·A / (2·L): the mean distance a ray travels before it crosses one of isotropic lines of
    total length L spread over the area A (here the segments' bounding box). Only the first ray
    length of :func:`_ray_hits` depends on it, never the hits."""
    lo, hi = segments.reshape(-1, 2).min(axis=0), segments.reshape(-1, 2).max(axis=0)
    total = float(np.hypot(*(segments[:, 1] - segments[:, 0]).T).sum())
    area = float(np.prod(hi - lo))
    return math.pi * area / (2 * total) if total > 0 and area > 0 else float(np.max(hi - lo))


def _ray_hits(origins, directions, segments, max_len, first_len=None, growth=4.0):
    """Distance along each ray to the first segment it crosses beyond a tiny start offset.

    Parameters
    ----------
    origins, directions : (n, 2) float64
        Ray starts and unit directions.
    segments : (m, 2, 2) float64
        The lines a ray can hit.
    max_len : float
        Longest ray; a ray that crosses nothing within it gets inf. Crossings closer than
        ``max_len · 1e-9`` to the start (the ray's own segment) do not count.
    first_len : float, optional
        Length of the first, bounded rays; default twice the network's mean free path
        (:func:`_mean_free_path`). ``first_len = max_len`` casts every ray at full length at once.
    growth : float, default 4
        Each round lengthens the rays that have not hit yet by this factor, up to ``max_len``.

    Returns
    -------
    t : (n,) float64
        Distance to the first crossing (inf: none within ``max_len``).
    n_pairs : int
        (ray, segment) pairs the spatial index reported over all rounds — the work done, which
        grows with the total length of the rays cast, not with n · m.

    Notes
    -----
    One STRtree (shapely/GEOS) over the segments; rays are cast bounded and only the rays without
    a hit are cast again, longer. A crossing at distance t < ℓ lies on the bounded ray of length ℓ
    as well as on the full one, so the nearest crossing found on the bounded ray is the nearest on
    the full ray: the hits are those of one domain-long ray per end (``first_len = max_len``), at a
    cost near-linear in the number of rays when most hit within a few mean free paths.
    """
    origins = np.asarray(origins, np.float64)
    directions = np.asarray(directions, np.float64)
    best = np.full(len(origins), np.inf)
    if not len(origins) or not len(segments):
        return best, 0
    tree = shapely.STRtree(shapely.linestrings(segments))
    length = min(max_len, 2 * _mean_free_path(segments) if first_len is None else first_len)
    todo = np.arange(len(origins))
    n_pairs = 0
    while len(todo):
        p, d = origins[todo], directions[todo]
        rays = shapely.linestrings(np.stack([p, p + d * length], axis=1))
        r, s = tree.query(rays, predicate="intersects")
        n_pairs += len(r)
        t = _crossing_distance(p[r], d[r], segments[s])
        t = np.where(t > max_len * 1e-9, t, np.inf)
        hit = np.full(len(todo), np.inf)
        np.minimum.at(hit, r, t)
        best[todo] = hit
        if length >= max_len:
            break
        todo = todo[~np.isfinite(hit)]
        length = min(max_len, length * growth)
    return best, n_pairs


def dangling_extensions(segments: np.ndarray, grid: float, max_len: float):
    """Dangling ends (nodes of degree 1) and the segments that extend them to the first line hit.

    Each end casts a ray along its own segment; the first crossing within ``max_len`` is found by
    bounded rays on a spatial index (:func:`_ray_hits`), with the hits of domain-long rays.

    Returns
    -------
    ext : (k, 2, 2) float64
        One extension per dangling end (dangling ends that hit nothing are left out).
    parent : (k,) int64
        Index into ``segments`` of the segment each extension continues.
    n_dangling : int
    """
    q = np.round(segments.reshape(-1, 2) / grid).astype(np.int64)
    _, inverse, counts = unique_rows(q)
    deg1 = counts[inverse.ravel()] == 1
    ends = np.flatnonzero(deg1)
    if not len(ends):
        return np.empty((0, 2, 2)), np.empty(0, np.int64), 0
    seg = ends // 2
    tip = segments[seg, ends % 2]
    other = segments[seg, 1 - ends % 2]
    d = tip - other
    d /= np.hypot(d[:, 0], d[:, 1])[:, None]
    t, _ = _ray_hits(tip, d, segments, max_len)
    ok = np.isfinite(t)
    ext = np.stack([tip[ok], tip[ok] + d[ok] * t[ok, None]], axis=1)
    return ext, seg[ok], len(ends)


def polygonize_segments(segments: np.ndarray) -> np.ndarray:
    """Faces of a noded network as an array of polygons (dangles and cut edges dropped),
    oriented counter-clockwise."""
    faces = shapely.get_parts(shapely.polygonize(shapely.linestrings(segments)))
    return shapely.orient_polygons(faces)
