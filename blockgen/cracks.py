"""Potential cracks (expanded DEM, Jiang et al. §3.1; docs/blocks.md §4): subdivide intact blocks into glued convex sub-blocks.

In the expanded DEM of Jiang et al. (docs/sources.md §1) the intact rock between joints is itself made of
smaller blocks bonded by *potential cracks*: glued contacts with the strength of intact rock (c, φ,
T) that fail by Mohr–Coulomb or tension and from then on behave as joints (docs/blocks.md §4). This
module draws those cracks inside the already convex blocks of a model; the builder adds them to its
cut network as ``glued`` contacts with ``contact_source == SOURCE_CRACK`` (``-3``).

Patterns (sub-block area ≈ ``size_m²`` for both, away from the parent block's boundary)
---------------------------------------------------------------------------------------
``"voronoi"``
    Voronoi cells of seed points (GEOS ``voronoi_polygons``) clipped to each parent block. The seeds
    are a hexagonal lattice of spacing ``a = size_m·√(2/√3)`` (hexagon area ``(√3/2)a² = size_m²``),
    rotated by ``angle_deg``, with a seeded random origin, each point moved uniformly inside a disk
    of radius ``jitter·a`` (``jitter`` 0 gives regular hexagons; ``jitter`` <= 0.5 keeps seeds apart
    by ``(1 − 2·jitter)·a``). The Voronoi cells of any point set are convex, so every piece
    (cell ∩ convex parent) is convex. **Slivers**: while a piece's mean width ``2·area/perimeter``
    is below ``sliver_width_m`` (the builder's sliver rule), the seed of the thinnest such piece is
    removed and the parent re-tessellated (likewise when an edge the cracks created is shorter than
    the minimum edge ``2d``) — the remaining cells are still Voronoi cells, hence
    convex, and cover the parent.
``"triangular"``
    Equilateral triangles of side ``t = size_m·√(4/√3)`` (area ``(√3/4)t² = size_m²``): three
    families of lines at ``angle_deg``, ``+60°``, ``+120°`` through the lattice nodes, seeded random
    origin. **Slivers**: the thinnest piece below ``sliver_width_m`` is merged with the adjacent
    piece of the same parent whose union with it is convex (longest shared edge first). Two clipped
    lattice triangles always have a convex union (the angles at the ends of their shared edge add to
    120° at a lattice node, 180° on the parent's boundary), so every sliver with a neighbour is
    resolved; one without a convex union is kept and reported. A piece with a new edge shorter than
    the minimum edge (a lattice line passing near a corner of the parent) is merged the same way.

Which blocks are subdivided: rock blocks (region 0; excavated stages too with
``include_excavated``), optionally only those within ``within_m`` of an excavation outline and/or
whose representative point (``shapely.point_on_surface``) lies inside ``zone_xy_m``.

Reproducibility: the seed points and the lattice origin are drawn from one generator, so the same
``seed`` gives the same cracks; the builder passes ``SeedSequence(seed)`` child number
``len(joint_sets)`` (the joint sets use children 0 .. n − 1).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, Optional

import numpy as np
import shapely
from pydantic import Field, model_validator

from ..dfn.specs import Bool, Float, field_error, spec

__all__ = ["Cracks", "CRACK_PATTERNS", "crack_segments", "select_parents"]

CRACK_PATTERNS = ("voronoi", "triangular")
_Point = Annotated[tuple[Annotated[Float, Field(ge=-1e7, le=1e7)], Annotated[Float, Field(ge=-1e7, le=1e7)]],
                   Field(strict=False)]
#: a union of two pieces is convex when its convex hull is larger by at most this fraction of its area
_HULL_RTOL = 1e-9


@spec(key="cracks.")
class Cracks:
    """Settings of the potential-crack subdivision (see the module docstring).

    Parameters
    ----------
    size_m : float
        Target sub-block size: pieces of area ≈ ``size_m²`` (> 0).
    pattern : {"voronoi", "triangular"}, default "voronoi"
    jitter : float, default 0.3
        Voronoi only: seed displacement radius / lattice spacing, 0 <= jitter <= 0.5.
    angle_deg : float, default 0.0
        Orientation of the seed lattice / of the first family of triangle sides.
    within_m : float, optional
        Only blocks within this distance (>= 0) of an excavation outline.
    zone_xy_m : (k, 2) array_like, optional
        Only blocks whose representative point lies inside this polygon.
    include_excavated : bool, default False
        Subdivide the blocks of excavation stages too (they are removed by the solver later).
    """

    size_m: Annotated[Float, Field(gt=0, le=1e6, description="target sub-block size: pieces of area ≈ "
                                                            "size_m²")]
    pattern: Annotated[Literal["voronoi", "triangular"], Field(
        description="Voronoi cells of a jittered hexagonal lattice, or triangles")] = "voronoi"
    jitter: Annotated[Float, Field(ge=0, le=0.5, description="Voronoi seed displacement / lattice "
                                                             "spacing")] = 0.3
    angle_deg: Annotated[Float, Field(ge=-360, le=360, description="orientation of the seed lattice or "
                                                                   "of the triangles")] = 0.0
    within_m: Annotated[Optional[Float], Field(ge=0, le=1e6, description="only blocks within this "
                                               "distance of an excavation outline")] = None
    zone_xy_m: Annotated[Optional[tuple[_Point, ...]], Field(
        strict=False, min_length=3, max_length=10000,
        description="only blocks whose representative point lies inside this polygon")] = None
    include_excavated: Annotated[Bool, Field(description="subdivide the blocks of excavation stages "
                                                         "too")] = False

    @model_validator(mode="after")
    def _simple_zone(self) -> Cracks:
        if self.zone_xy_m is not None:
            poly = shapely.Polygon(self.zone_xy_m)
            if not poly.is_valid or poly.area <= 0:
                raise field_error(self, "zone_xy_m", "must be a simple polygon with positive area",
                                  [list(p) for p in self.zone_xy_m])
        return self


def select_parents(faces, region, cracks: Cracks, excavations) -> np.ndarray:
    """Indices of the faces to subdivide (see the module docstring)."""
    ok = np.ones(len(faces), bool) if cracks.include_excavated else region == 0
    if cracks.within_m is not None:
        if not excavations:
            raise ValueError("cracks.within_m: the model has no excavations to measure from")
        opening = shapely.union_all([e.polygon() for e in excavations])
        ok &= shapely.distance(faces, opening) <= cracks.within_m
    if cracks.zone_xy_m is not None:
        ok &= shapely.contains(shapely.Polygon(cracks.zone_xy_m), shapely.point_on_surface(faces))
    return np.flatnonzero(ok)


def _rotation(angle_deg):
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return np.array([[c, -s], [s, c]])


def _hex_seeds(bounds, cracks: Cracks, rng) -> np.ndarray:
    """Jittered hexagonal lattice covering ``bounds`` (minx, miny, maxx, maxy), rotated."""
    a = cracks.size_m * math.sqrt(2 / math.sqrt(3))
    minx, miny, maxx, maxy = bounds
    centre = np.array([(minx + maxx) / 2, (miny + maxy) / 2])
    half = 0.5 * math.hypot(maxx - minx, maxy - miny) + 2 * a
    rows = np.arange(-math.ceil(half / (a * math.sqrt(3) / 2)), math.ceil(half / (a * math.sqrt(3) / 2)) + 1)
    cols = np.arange(-math.ceil(half / a) - 1, math.ceil(half / a) + 2)
    r, c = np.meshgrid(rows, cols, indexing="ij")
    origin = rng.random(2) * [a, a * math.sqrt(3) / 2]
    local = np.column_stack([(c + 0.5 * (r % 2)).ravel() * a, r.ravel() * a * math.sqrt(3) / 2]) + origin
    n = len(local)
    rad = cracks.jitter * a * np.sqrt(rng.random(n))
    phi = 2 * math.pi * rng.random(n)
    local = local + np.column_stack([rad * np.cos(phi), rad * np.sin(phi)])
    pts = local @ _rotation(cracks.angle_deg).T + centre
    keep = ((pts[:, 0] >= minx - a) & (pts[:, 0] <= maxx + a) & (pts[:, 1] >= miny - a)
            & (pts[:, 1] <= maxy + a))
    return pts[keep]


def _width(polys):
    return 2 * shapely.area(polys) / shapely.length(polys)


def _badness(pieces, parents, sliver_width_m, min_edge_m, near_m):
    """min(width / sliver_width_m, shortest new edge / min_edge_m) per piece: < 1 is a bad piece.

    ``parents`` is the parent of each piece (or one parent for all). A *new* edge has an end that
    is not a vertex of the parent (farther than ``near_m``): an edge the cracks created. The
    parent's own short edges are not the cracks' doing and are not counted.
    """
    pieces = np.atleast_1d(pieces)
    corners = np.broadcast_to(shapely.extract_unique_points(np.asarray(parents, dtype=object)),
                              pieces.shape)
    score = _width(pieces) / sliver_width_m
    coords, index = shapely.get_coordinates(shapely.get_exterior_ring(pieces), return_index=True)
    same = index[1:] == index[:-1]
    a, b, owner = coords[:-1][same], coords[1:][same], index[:-1][same]
    d_a = shapely.distance(shapely.points(a), corners[owner])
    d_b = shapely.distance(shapely.points(b), corners[owner])
    new = (d_a > near_m) | (d_b > near_m)
    ratio = np.hypot(*(b - a).T) / min_edge_m
    edge_score = np.full(len(pieces), np.inf)
    np.minimum.at(edge_score, owner[new], ratio[new])
    return np.minimum(score, edge_score)


def _voronoi_all(polys, groups, seeds, tol, stats, spacing_m):
    """Crack segments of many parents at once; parents with a bad piece go to
    :func:`_voronoi_parent` (seed removal). Returns (segments, number of subdivided parents)."""
    par = np.array([g[0] for g in groups])
    sizes = np.array([len(g[1]) for g in groups])
    owner = np.repeat(np.arange(len(groups)), sizes)
    mp = shapely.multipoints(seeds[np.concatenate([g[1] for g in groups])], indices=owner)
    cells = shapely.voronoi_polygons(mp, extend_to=polys[par], ordered=True)
    parts, which = shapely.get_parts(cells, return_index=True)
    pieces = shapely.intersection(parts, polys[par][which])
    bad = np.bincount(which, _badness(pieces, polys[par][which], *tol) < 1, len(groups)) > 0
    out, n_sub = [], 0
    good = np.flatnonzero(~bad)
    if len(good):
        edges = shapely.voronoi_polygons(mp[good], extend_to=polys[par[good]], only_edges=True)
        segs = _lines_to_segments(shapely.intersection(edges, polys[par[good]]))
        if len(segs):
            out.append(segs)
        n_sub += len(good)
        stats["n_pieces"] += int(sizes[good].sum())
    for g in np.flatnonzero(bad).tolist():
        segs, n = _voronoi_parent(polys[par[g]], seeds[groups[g][1]], tol, stats, spacing_m)
        if len(segs):
            out.append(segs)
            n_sub += 1
            stats["n_pieces"] += int(n)
    return out, n_sub


def _lines_to_segments(geoms) -> np.ndarray:
    """2-point segments of (multi)line geometries, zero-length ones dropped."""
    parts = shapely.get_parts(geoms)
    parts = parts[shapely.get_type_id(parts) == 1]
    if not len(parts):
        return np.empty((0, 2, 2))
    coords, index = shapely.get_coordinates(parts, return_index=True)
    same = index[1:] == index[:-1]
    out = np.stack([coords[:-1][same], coords[1:][same]], axis=1)
    return out[np.any(out[:, 0] != out[:, 1], axis=1)]


def _voronoi_parent(poly, pts, tol, stats, spacing_m):
    """Crack segments of one parent from its seed points (seeds of bad pieces removed).

    Each round removes the seed of the worst bad piece and of every other bad piece whose seed is
    farther than ``3·spacing_m`` from the seeds already chosen in that round (a seed's removal only
    changes the cells next to it), so a large parent needs few rounds.
    """
    while len(pts) >= 2:
        cells = shapely.get_parts(shapely.voronoi_polygons(shapely.multipoints(pts), extend_to=poly,
                                                           ordered=True))
        pieces = shapely.intersection(cells, poly)
        bad = _badness(pieces, poly, *tol)
        order = np.argsort(bad, kind="stable")
        order = order[bad[order] < 1]
        if not len(order):
            break
        chosen = []
        for k in order.tolist():
            if all(math.dist(pts[k], pts[c]) > 3 * spacing_m for c in chosen):
                chosen.append(k)
        if len(pts) - len(chosen) < 1:
            chosen = chosen[:1]
        pts = np.delete(pts, chosen, axis=0)
        stats["seeds_removed"] += len(chosen)
    if len(pts) < 2:
        return np.empty((0, 2, 2)), 1
    edges = shapely.voronoi_polygons(shapely.multipoints(pts), extend_to=poly, only_edges=True)
    return _lines_to_segments(shapely.intersection(edges, poly)), len(pts)


def _triangular_parent(poly, cracks, origin, tol, stats):
    """Crack segments of one parent cut by the triangular lattice (bad pieces merged)."""
    t = cracks.size_m * math.sqrt(4 / math.sqrt(3))
    rot = _rotation(cracks.angle_deg)
    e1 = rot @ np.array([t, 0.0])
    e2 = rot @ np.array([t / 2, t * math.sqrt(3) / 2])
    basis = np.column_stack([e1, e2])
    uv = np.linalg.solve(basis, (np.asarray(poly.exterior.coords) - origin).T).T
    i0, j0 = np.floor(uv.min(axis=0)).astype(int) - 1
    i1, j1 = np.ceil(uv.max(axis=0)).astype(int) + 1
    ii, jj = np.meshgrid(np.arange(i0, i1 + 1), np.arange(j0, j1 + 1), indexing="ij")
    ii, jj = ii.ravel(), jj.ravel()

    def node(i, j):
        return origin + np.outer(i, e1) + np.outer(j, e2)

    up = np.stack([node(ii, jj), node(ii + 1, jj), node(ii, jj + 1)], axis=1)
    down = np.stack([node(ii + 1, jj), node(ii + 1, jj + 1), node(ii, jj + 1)], axis=1)
    tri = np.concatenate([up, down])
    n_cells = len(ii)
    key = {(int(i), int(j), k): k * n_cells + m for k in (0, 1)
           for m, (i, j) in enumerate(zip(ii.tolist(), jj.tolist()))}
    pieces = shapely.intersection(shapely.polygons(tri), poly)
    area = shapely.area(pieces)
    nonempty = area > 0
    # lattice edges between an up and a down triangle: (up id, down id, end a, end b)
    pairs, ends = [], []
    for m, (i, j) in enumerate(zip(ii.tolist(), jj.tolist())):
        for (di, dj), (pa, pb) in (((0, 0), ((i + 1, j), (i, j + 1))),
                                    ((-1, 0), ((i, j), (i, j + 1))),
                                    ((0, -1), ((i, j), (i + 1, j)))):
            other = key.get((i + di, j + dj, 1))
            if other is not None and nonempty[m] and nonempty[other]:
                pairs.append((m, other))
                ends.append((pa, pb))
    if not pairs:
        return np.empty((0, 2, 2)), int(nonempty.sum())
    pairs = np.array(pairs)
    ends = np.array(ends, float)
    seg_xy = np.stack([node(ends[:, 0, 0], ends[:, 0, 1]), node(ends[:, 1, 0], ends[:, 1, 1])], axis=1)
    clipped = shapely.intersection(shapely.linestrings(seg_xy), poly)
    shared = shapely.length(clipped)
    live = shared > 0
    pairs, clipped, shared = pairs[live], clipped[live], shared[live]
    # union-find over pieces; merge slivers into a neighbour with a convex union
    group = np.arange(len(tri))
    members = {int(g): [int(g)] for g in np.flatnonzero(nonempty)}
    geom = {g: pieces[g] for g in members}
    blocked = set()

    ids0 = list(members)
    score = dict(zip(ids0, _badness(np.array([geom[g] for g in ids0], dtype=object), poly, *tol)
                     .tolist())) if ids0 else {}
    while len(members) > 1:
        open_ = [g for g in members if g not in blocked and score[g] < 1]
        if not open_:
            break
        g = min(open_, key=lambda k: score[k])
        ga, gb = group[pairs[:, 0]], group[pairs[:, 1]]
        across = (ga != gb) & ((ga == g) | (gb == g))
        lengths = {}
        for a_, b_, s in zip(ga[across].tolist(), gb[across].tolist(), shared[across].tolist()):
            o = b_ if a_ == g else a_
            lengths[o] = lengths.get(o, 0.0) + s
        best = None
        for o in sorted(lengths, key=lambda k: -lengths[k]):
            # the ends of the removed crack stay as vertices on straight edges: drop them
            union = shapely.simplify(shapely.union(geom[g], geom[o]), tol[2])
            # convex up to round-off: the hull adds no area (robust to the ulp-scale double
            # vertices that clipping leaves where both pieces meet the parent's boundary)
            if (union.geom_type == "Polygon"
                    and shapely.convex_hull(union).area - union.area <= _HULL_RTOL * union.area):
                best = (o, union)
                break
        if best is None:
            blocked.add(g)
            stats["slivers_kept"] += 1
            continue
        o, union = best
        group[group == o] = g
        members[g] += members.pop(o)
        geom[g] = union
        geom.pop(o)
        score.pop(o)
        score[g] = float(_badness(np.array([union], dtype=object), poly, *tol)[0])
        stats["pieces_merged"] += 1
    keep = group[pairs[:, 0]] != group[pairs[:, 1]]
    return _lines_to_segments(clipped[keep]), len(members)


def crack_segments(faces, parents, cracks: Cracks, rng, sliver_width_m: float, min_edge_m: float,
                   near_m: float):
    """Crack segments inside the faces ``faces[parents]`` (convex polygons).

    A piece is *bad* when its mean width ``2·area/perimeter`` is below ``sliver_width_m`` or when an
    edge the cracks created (one end not a vertex of the parent, farther than ``near_m``) is
    shorter than ``min_edge_m``; bad pieces are removed as the module docstring describes (seed
    removed, or merged into a neighbour with a convex union).

    Returns
    -------
    segments : (n, 2, 2) float64
        2-point crack segments, each inside one parent and ending on its boundary or on another
        crack.
    stats : dict
        ``n_parents``, ``n_subdivided`` (parents cut into >= 2 pieces), ``n_pieces`` (pieces of the
        subdivided parents before noding), ``seeds_removed`` (voronoi) or ``pieces_merged`` /
        ``slivers_kept`` (triangular).
    """
    stats = {"n_parents": int(len(parents)), "n_subdivided": 0, "n_pieces": 0}
    tol = (sliver_width_m, min_edge_m, near_m)
    out = []
    if not len(parents):
        return np.empty((0, 2, 2)), stats
    polys = faces[parents]
    if cracks.pattern == "voronoi":
        stats["seeds_removed"] = 0
        seeds = _hex_seeds(shapely.total_bounds(polys), cracks, rng)
        tree = shapely.STRtree(shapely.points(seeds))
        f, p = tree.query(polys, predicate="contains_properly")
        order = np.argsort(f, kind="stable")
        f, p = f[order], p[order]
        split = np.flatnonzero(np.diff(f)) + 1
        groups = [(int(fs[0]), ps) for fs, ps in zip(np.split(f, split), np.split(p, split))
                  if len(ps) >= 2]
        if groups:
            spacing = cracks.size_m * math.sqrt(2 / math.sqrt(3))
            out, stats["n_subdivided"] = _voronoi_all(polys, groups, seeds, tol, stats, spacing)
    else:
        stats["pieces_merged"] = 0
        stats["slivers_kept"] = 0
        minx, miny, _, _ = shapely.total_bounds(polys)
        t = cracks.size_m * math.sqrt(4 / math.sqrt(3))
        origin = np.array([minx, miny]) + rng.random(2) * t
        for poly in polys:
            segs, n = _triangular_parent(poly, cracks, origin, tol, stats)
            if len(segs):
                out.append(segs)
                stats["n_subdivided"] += 1
                stats["n_pieces"] += int(n)
    segs = np.concatenate(out) if out else np.empty((0, 2, 2))
    return segs, stats
