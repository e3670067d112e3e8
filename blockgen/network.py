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
           "segment_keys", "exterior_coords"]


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


def node(segments: np.ndarray, grid: float, chain: bool = False) -> np.ndarray:
    """Node 2-point segments and return the noded 2-point segments.

    GEOS ``unary_union`` with ``grid_size`` runs snap-rounding noding: every output vertex lies on
    the ``grid`` (a power of two, see :func:`snap_to_grid`), so two intersections closer than the
    grid become one node and no edge shorter than the grid can appear.

    The output lists, input segment by input segment, the pieces of each along it and oriented like
    it (a piece two inputs share comes once, with the first). With ``chain`` the segments go to
    GEOS joined into chains (:func:`_node_chains`): the same output at a fraction of the cost for
    a noded network with additions, where most segments share endpoints; where the chained pieces
    cannot be traced back to their segments (overlapping inputs) the segments go one by one.
    """
    segments = np.asarray(segments, np.float64).reshape(-1, 2, 2)
    out = _node_chains(segments, grid) if chain else None
    if out is None:
        out = _noded_pieces(shapely.linestrings(segments), grid)
    return out[np.any(out[:, 0] != out[:, 1], axis=1)]


def _noded_pieces(lines, grid: float) -> np.ndarray:
    """The 2-point pieces, in GEOS's output order, of the lines ``lines`` snap-round noded."""
    merged = shapely.unary_union(lines, grid_size=grid)
    if shapely.is_empty(merged):
        return np.empty((0, 2, 2))
    # ragged arrays: no Python object per output line
    _, coords, offsets = shapely.to_ragged_array([shapely.multilinestrings(shapely.get_parts(merged))
                                                  if merged.geom_type != "MultiLineString"
                                                  else merged])
    ends = np.zeros(len(coords), bool)
    ends[offsets[0][1:] - 1] = True
    return np.stack([coords[:-1][~ends[:-1]], coords[1:][~ends[:-1]]], axis=1)


def _node_chains(segments: np.ndarray, grid: float):
    """:func:`node`'s pieces (zero-length ones included) with the segments joined into chains, or
    None when chaining does not pay or the pieces cannot be traced back to their segments.

    GEOS prepares a hot-pixel shuffle (a ``std::random_device``) per input line: with 2-point lines
    that is about half of the noding time. Chains (:func:`chain_segments`) are noded into the same
    pieces; GEOS lists them chain after chain, along each chain, a piece shared by two chains once
    (with the first), so :func:`trace_pieces` finds the segments each piece lies on. A piece goes
    to the lowest-numbered of its segments, oriented like it, and sorting by (segment, position
    along it) gives the order of segment-by-segment noding.
    """
    from ._network_kernels import chain_segments, trace_pieces

    if len(segments) < 2:
        return None
    seg, rev, start = chain_segments(_exact_node_ids(segments.reshape(-1, 2)).reshape(-1, 2),
                                     2 * len(segments))
    n_chains = len(start) - 1
    if n_chains > 0.8 * len(segments):
        return None
    verts, vert_chain = _chain_vertices(segments, seg, rev, start)
    pieces = _noded_pieces(shapely.linestrings(verts, indices=vert_chain), grid)
    # GEOS rounds every vertex to the grid (half up): the chain vertices as they appear in pieces
    ids = _exact_node_ids(np.concatenate([pieces.reshape(-1, 2),
                                          np.floor(verts / grid + 0.5) * grid]))
    piece_node, vert_node = ids[:2 * len(pieces)].reshape(-1, 2), ids[2 * len(pieces):]
    none = np.empty(0, np.int64)
    rec = trace_pieces(piece_node, vert_node, start, none, none)
    if not len(rec[0]) and len(pieces):  # gaps: again with the pieces at each node
        half = np.argsort(piece_node.ravel(), kind="stable")
        half_ptr = np.concatenate([[0], np.cumsum(np.bincount(piece_node.ravel(),
                                                              minlength=int(ids.max()) + 1))])
        rec = trace_pieces(piece_node, vert_node, start, half_ptr, half)
    rec_piece, rec_pos, rec_flip = rec
    if len(np.unique(rec_piece)) != len(pieces):
        return None
    owner = seg[rec_pos]
    backwards = rev[rec_pos] ^ rec_flip
    walk = np.arange(len(rec_piece))
    first = np.lexsort((owner, rec_piece))  # per piece, its lowest-numbered segment first
    keep = first[np.concatenate([[True], rec_piece[first][1:] != rec_piece[first][:-1]])]
    out = pieces[rec_piece[keep]]
    out[backwards[keep]] = out[backwards[keep]][:, ::-1]
    return out[np.lexsort((np.where(backwards[keep], -walk[keep], walk[keep]), owner[keep]))]


def _exact_node_ids(points: np.ndarray) -> np.ndarray:
    """An id per point, equal for exactly equal coordinates (-0.0 counted as 0.0)."""
    return unique_rows((np.asarray(points, np.float64) + 0.0).view(np.int64))[1].ravel()


def _chain_vertices(segments, seg, rev, start):
    """Vertices of the chains (:func:`chain_segments`) and the chain of each vertex: chain c's
    vertex k + c starts its position k, the last one ends it."""
    n_chains = len(start) - 1
    chain_of = np.repeat(np.arange(n_chains), np.diff(start))
    heads = start[:-1] + np.arange(n_chains)
    rest = np.arange(len(seg)) + chain_of + 1
    verts = np.empty((len(seg) + n_chains, 2))
    verts[heads] = segments[seg[start[:-1]], rev[start[:-1]].astype(np.int64)]
    verts[rest] = segments[seg, 1 - rev.astype(np.int64)]
    vert_chain = np.empty(len(verts), np.int64)
    vert_chain[heads] = np.arange(n_chains)
    vert_chain[rest] = chain_of
    return verts, vert_chain


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


def exterior_coords(faces):
    """(coords, face index) of the closed exterior rings of the polygons ``faces``: the result of
    ``shapely.get_coordinates(shapely.get_exterior_ring(faces), return_index=True)``, read from the
    polygons directly when none has a hole (no ring object per face, which costs more than the
    coordinates)."""
    if shapely.get_num_interior_rings(faces).any():
        return shapely.get_coordinates(shapely.get_exterior_ring(faces), return_index=True)
    return shapely.get_coordinates(faces, return_index=True)
