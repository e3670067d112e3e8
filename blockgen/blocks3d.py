"""3D block models: a box cut by persistent joint sets or by the disks of a DFN realization.

Cutting (docs/blocks.md §8). The box is cut by one plane after another
(:func:`rockmass.blockgen.polyhedra.split`). A persistent plane cuts every block it crosses. A disk
(a fracture of finite size) cuts, as 3DEC does, every block whose cap on the disk's plane comes
within the disk's radius of its centre — along the whole plane inside that block; the part of such a
cut that lies outside the disk is a *fictitious* face, glued with intact-rock strength.

In-situ blocks. Two pieces that share part of a cut are separated only where the shared polygon lies
wholly inside the fracture; where any of it is fictitious, the rock is continuous across it and the
two pieces belong to one in-situ block (union–find over those links). So a disk that does not cut a
block through leaves it one in-situ block, with a real joint face of the disk's area inside it.

Each link (piece a, piece b, label) records the shared area and its real (fractured) part: the real
part of a polygon that lies wholly inside the disk (all its vertices within the radius — exact, the
polygon and the disk being convex) is its whole area, else the area of its intersection with the
disk, computed on a 256-gon (relative error ≤ (2π/256)²/6 ≈ 5·10⁻⁵ of the disk area).

Speed. The cutting by fracture planes and the piece moments run in numba kernels on a flat layout of
all pieces (:mod:`rockmass.blockgen._polyhedra_kernels`, imported on first use; same rule as
:func:`~rockmass.blockgen.polyhedra.split`), and shared faces are found by bounding box (shapely
STRtree) and clipped against each other, convex polygon by convex polygon, in a kernel too.
``_USE_KERNELS = False`` selects the reference numpy cutting path.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely

from .polyhedra import Polyhedron, _from_flat, _to_flat, box_polyhedron, plane_basis, split

if TYPE_CHECKING:
    from .openings3d import Tunnel

__all__ = ["Planes", "BlockSet3D", "persistent_set_planes", "disk_planes", "cut_box"]

#: vertices of the polygon standing for a disk in real-area computations.
DISK_POLYGON_VERTICES = 256
#: length tolerance / box diagonal.
TOL_FRACTION = 1e-10
#: cut and integrate in the numba kernels (False: the reference numpy path through ``split``).
_USE_KERNELS = True


@dataclass(frozen=True)
class Planes:
    """Cutting planes n·x = d: unit ``normal (n, 3)``, ``offset_m (n,)``, ``label (n,)`` (>= 0),
    and for disks ``centre_m (n, 3)`` and ``radius_m (n,)`` (``inf`` for a persistent plane)."""

    normal: np.ndarray
    offset_m: np.ndarray
    label: np.ndarray
    centre_m: np.ndarray
    radius_m: np.ndarray

    def __len__(self) -> int:
        return len(self.offset_m)


@dataclass(frozen=True)
class BlockSet3D:
    """Pieces of a cut box and the in-situ blocks they form.

    ``pieces`` are the convex polyhedra; ``volume_m3 (n,)`` and ``centroid_m (n, 3)`` theirs;
    ``block_id (n,)`` the in-situ block of each piece (0 .. n_blocks − 1); ``links (k, 3)`` int rows
    (piece a, piece b, plane index j) — piece a lies on the side n_j·x ≤ d_j — with
    ``link_area_m2`` and ``link_real_area_m2`` (the fractured part; the rest is fictitious, glued).
    ``planes`` are all the cutting planes (fractures first, then tunnel walls, labelled −2 − k);
    ``box_m`` is the domain; ``excavated (n,)`` marks the pieces inside a tunnel (``block_id`` −1).
    ``second_moment_m5 (n, 3, 3)``: ∫x xᵀ dV of each piece about the origin; ``surface_area_m2
    (n,)``: the area of each piece's faces; ``timings_s``: seconds spent cutting, on moments, on links
    and on grouping.
    """

    pieces: tuple[Polyhedron, ...]
    volume_m3: np.ndarray
    centroid_m: np.ndarray
    block_id: np.ndarray
    links: np.ndarray
    link_area_m2: np.ndarray
    link_real_area_m2: np.ndarray
    box_m: np.ndarray
    excavated: np.ndarray
    planes: Planes | None
    second_moment_m5: np.ndarray
    surface_area_m2: np.ndarray
    timings_s: dict

    @property
    def link_label(self) -> np.ndarray:
        """Label of each link's plane (fracture or set id; −2 − k for tunnel k's walls)."""
        return self.planes.label[self.links[:, 2]] if len(self.links) else np.zeros(0, np.int64)

    @property
    def n_blocks(self) -> int:
        return int(self.block_id.max()) + 1 if len(self.block_id) else 0

    def block_volumes_m3(self) -> np.ndarray:
        """Volume of each in-situ block (sum of its pieces)."""
        rock = self.block_id >= 0
        return np.bincount(self.block_id[rock], weights=self.volume_m3[rock], minlength=self.n_blocks)


def persistent_set_planes(box_m, normal, spacing_m: float, origin_m=(0.0, 0.0, 0.0),
                          label: int = 0) -> Planes:
    """The planes of one persistent set crossing the box: normal n, through ``origin_m`` and every
    multiple of ``spacing_m`` from it along n.

    >>> len(persistent_set_planes([[0, 0, 0], [1, 1, 1]], [0, 0, 1], 0.25))
    3
    """
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    corners = np.array(np.meshgrid(*np.asarray(box_m, float).T)).reshape(3, -1).T
    d0 = float(np.dot(n, origin_m))
    proj = corners @ n
    k = np.arange(math.ceil((proj.min() - d0) / spacing_m), math.floor((proj.max() - d0) / spacing_m) + 1)
    offsets = d0 + k * spacing_m
    offsets = offsets[(offsets > proj.min()) & (offsets < proj.max())]
    m = len(offsets)
    return Planes(np.tile(n, (m, 1)), offsets, np.full(m, label, np.int64),
                  np.zeros((m, 3)), np.full(m, np.inf))


def disk_planes(network) -> Planes:
    """The planes of a :class:`rockmass.dfn.DiskNetwork`, labelled by fracture index."""
    normal = np.asarray(network.normal, float)
    centre = np.asarray(network.centre_m, float)
    return Planes(normal, np.einsum("ij,ij->i", normal, centre), np.arange(len(normal), dtype=np.int64),
                  centre, np.asarray(network.radius_m, float))


def _join(*planes: Planes) -> Planes:
    return Planes(*(np.concatenate([getattr(p, f) for p in planes])
                    for f in ("normal", "offset_m", "label", "centre_m", "radius_m")))


def _touches_disk(cap: np.ndarray, normal, centre, radius) -> bool:
    """Does the cap polygon come within ``radius`` of the disk centre (in the plane)?"""
    if not math.isfinite(radius):
        return True
    e1, e2 = plane_basis(normal)
    polygon = shapely.Polygon(np.stack([cap @ e1, cap @ e2], axis=1))
    return polygon.distance(shapely.Point(centre @ e1, centre @ e2)) < radius


def cut_box(box_m, *planes: Planes, tunnels: tuple["Tunnel", ...] = (),
            tol_m: float | None = None) -> BlockSet3D:
    """Cut the box by ``planes`` (in order), then by the walls of ``tunnels``; group the pieces into
    in-situ blocks.

    Tunnel walls cut only the pieces that reach into the tunnel (their faces are labelled
    ``-2 - k`` for tunnel k); the pieces inside a tunnel are marked ``excavated`` and belong to no
    block (``block_id`` −1). A wall face between two rock pieces is fictitious (glued); a face of a
    rock piece whose partner was excavated is the free surface of the opening.

    >>> sets = [persistent_set_planes([[0, 0, 0], [1, 1, 1]], axis, 0.5, label=i)
    ...         for i, axis in enumerate(np.eye(3))]
    >>> blocks = cut_box([[0, 0, 0], [1, 1, 1]], *sets)
    >>> blocks.n_blocks, np.round(blocks.block_volumes_m3(), 12).tolist()[:2]
    (8, [0.125, 0.125])
    """
    clock = [time.perf_counter()]
    box = np.asarray(box_m, float)
    size = float(np.linalg.norm(box[1] - box[0]))
    tol = TOL_FRACTION * size if tol_m is None else float(tol_m)
    walls = [t.wall_planes(label=-2 - k) for k, t in enumerate(tunnels)]
    all_planes = _join(*planes, *walls) if planes or walls else None
    first_wall = sum(len(p) for p in planes)
    if _USE_KERNELS:
        flat = _cut_flat(box, all_planes, tunnels, first_wall, tol)
        pieces = _from_flat(*flat)
    else:
        pieces = [box_polyhedron(box)]
        bounds = [box[:1].copy(), box[1:].copy()]
        for j in range(first_wall):
            _cut_by_plane(pieces, bounds, all_planes, j, tol, inside=None)
        j = first_wall
        for tunnel, wall in zip(tunnels, walls):
            for _ in range(len(wall)):
                _cut_by_plane(pieces, bounds, all_planes, j, tol, inside=tunnel)
                j += 1
        flat = _to_flat(pieces)
    excavated = np.zeros(len(pieces), bool)
    vert_piece = np.repeat(np.repeat(np.arange(len(pieces)), np.diff(flat[3])), np.diff(flat[1]))
    for tunnel in tunnels:           # Tunnel.contains for every piece at once
        normal, offset = tunnel.halfspaces
        outside = ~(flat[0] @ normal.T <= offset + tol).all(axis=1)
        excavated |= np.bincount(vert_piece, weights=outside, minlength=len(pieces)) == 0
    clock.append(time.perf_counter())
    volume, first_moment, second_moment = _volumes(flat)
    centroid = first_moment / volume[:, None]
    clock.append(time.perf_counter())
    links, area, real = _links(flat, all_planes, tol * size, tol)
    clock.append(time.perf_counter())
    block_id = _components(len(pieces), links, area, real, excavated)
    clock.append(time.perf_counter())
    return BlockSet3D(tuple(pieces), volume, centroid, block_id, links, area, real, box, excavated,
                      all_planes, second_moment, _surface_areas(flat),
                      dict(zip(("cut", "moments", "links", "grouping"), np.diff(clock).tolist())))


def _cut_flat(box: np.ndarray, planes: Planes | None, tunnels, n_fractures: int, tol: float):
    """The box cut by ``planes`` in the numba kernel, as the flat layout (verts, face_start,
    face_label, piece_start): the first ``n_fractures`` everywhere, then each tunnel's walls only
    where a piece can reach into that tunnel."""
    flat = _to_flat([box_polyhedron(box)])
    if planes is None:
        return flat
    from ._polyhedra_kernels import cut_by_planes

    halfspaces = [tunnel.halfspaces for tunnel in tunnels]
    per_plane = np.r_[np.zeros(n_fractures, np.int64), [len(h[1]) for h in halfspaces for _ in h[1]]]
    region_start = np.zeros(len(planes) + 1, np.int64)
    np.cumsum(per_plane, out=region_start[1:])
    region_normal = np.concatenate([np.zeros((0, 3))] + [h[0] for h in halfspaces for _ in h[1]])
    region_offset = np.concatenate([np.zeros(0)] + [h[1] for h in halfspaces for _ in h[1]])
    f64 = np.float64
    return cut_by_planes(*flat, *(np.ascontiguousarray(a, f64) for a in
                                  (planes.normal, planes.offset_m, planes.centre_m, planes.radius_m,
                                   region_normal, region_offset)), region_start, 0, tol)


def _volumes(flat) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Volume (n,), first moment ∫x dV (n, 3) and second moment ∫x xᵀ dV (n, 3, 3) of every piece
    of the flat layout."""
    n = len(flat[3]) - 1
    volume, first, second = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3))
    if _USE_KERNELS:
        from ._polyhedra_kernels import piece_moments

        piece_moments(flat[0], flat[1], flat[3], volume, first, second)
    else:
        for i, piece in enumerate(_from_flat(*flat)):
            volume[i], first[i], second[i] = piece.moments()
    return volume, first, second


def _surface_areas(flat) -> np.ndarray:
    """Σ face areas of every piece: each face's area is half the norm of Σ_i v_i × v_{i+1} over its
    vertices (the vector area of a planar polygon), for all faces at once."""
    verts, face_start, _, piece_start = flat
    if len(verts) == 0:
        return np.zeros(len(piece_start) - 1)
    following = np.arange(1, len(verts) + 1)
    following[face_start[1:] - 1] = face_start[:-1]          # the last vertex of a face wraps
    cross = np.cross(verts, verts[following])
    face_area = 0.5 * np.linalg.norm(np.add.reduceat(cross, face_start[:-1], axis=0), axis=1)
    per_piece = np.add.reduceat(face_area, piece_start[:-1]) if len(face_area) else face_area
    return per_piece


def _cut_by_plane(pieces: list, bounds: list, planes: Planes, j: int, tol: float, inside) -> None:
    """Cut, in place, every piece that plane ``j`` crosses (and, for a disk, whose cap touches the
    disk; for a tunnel wall, that reaches into the tunnel ``inside``). ``bounds`` = [lo, hi] arrays
    of the pieces' bounding boxes, kept in step."""
    lo, hi = bounds
    n, d = planes.normal[j], planes.offset_m[j]
    centre, radius = planes.centre_m[j], planes.radius_m[j]
    reach = (hi - lo) / 2 @ np.abs(n)
    candidates = np.flatnonzero(np.abs((lo + hi) / 2 @ n - d) < reach - tol)
    if math.isfinite(radius):
        gap = np.linalg.norm(np.maximum(0.0, np.maximum(lo[candidates] - centre, centre - hi[candidates])),
                             axis=1)
        candidates = candidates[gap < radius]
    new_pieces = []
    for i in candidates:
        if inside is not None and not inside.reaches(pieces[i].vertices_m(), tol):
            continue
        below, above, cap = split(pieces[i], n, d, j, tol)
        if cap is None or not _touches_disk(cap, n, centre, radius):
            continue
        pieces[i] = below
        lo[i], hi[i] = below.vertices_m().min(axis=0), below.vertices_m().max(axis=0)
        new_pieces.append(above)
    if new_pieces:
        pieces.extend(new_pieces)
        bounds[0] = np.vstack([lo] + [p.vertices_m().min(axis=0) for p in new_pieces])
        bounds[1] = np.vstack([hi] + [p.vertices_m().max(axis=0) for p in new_pieces])


def _links(flat, planes: Planes | None, min_area_m2: float, tol_m: float):
    """Pairs of pieces sharing part of a cut: (a, b, plane index), shared area, real area.

    Faces carry the index of the plane that made them; on each plane the faces whose outward normal
    is +n (their piece lies below) are matched with those facing −n: candidate pairs by bounding
    box (shapely STRtree), shared polygon by clipping one convex face by the other in the plane
    (numba kernel; exact for convex polygons, and robust where faces only touch along an edge).
    ``flat`` is the pieces' flat layout (verts, face_start, face_label, piece_start); clipped vertices
    closer than ``tol_m`` are merged.
    """
    empty = np.zeros((0, 3), np.int64), np.zeros(0), np.zeros(0)
    verts, face_start, face_label, piece_start = flat
    cut = np.flatnonzero(face_label >= 0)
    if planes is None or not len(cut):
        return empty
    from ._polyhedra_kernels import clip_convex_pairs, disk_overlap, project_faces

    n_pieces = len(piece_start) - 1
    face_piece = np.repeat(np.arange(n_pieces), np.diff(piece_start))
    vert_piece = np.repeat(face_piece, np.diff(face_start))
    means = np.stack([np.bincount(vert_piece, weights=verts[:, c], minlength=n_pieces) for c in range(3)],
                     axis=1) / np.bincount(vert_piece, minlength=n_pieces)[:, None]
    # cut faces grouped by plane (stable: piece order within a plane), planes by first appearance
    cut = cut[np.argsort(face_label[cut], kind="stable")]
    plane_of = face_label[cut]
    starts = np.flatnonzero(np.r_[True, plane_of[1:] != plane_of[:-1]])
    ends = np.r_[starts[1:], len(cut)]
    e1, e2 = _plane_bases(planes.normal)
    lengths = np.diff(face_start)[cut]
    ring_start = np.zeros(len(cut) + 1, np.int64)
    np.cumsum(lengths, out=ring_start[1:])
    uv, lo, hi = np.empty((ring_start[-1], 2)), np.empty((len(cut), 2)), np.empty((len(cut), 2))
    project_faces(verts, face_start, cut, e1[plane_of], e2[plane_of], ring_start, uv, lo, hi)
    boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
    below = np.einsum("ij,ij->i", means[face_piece[cut]], planes.normal[plane_of]) < planes.offset_m[plane_of]
    pair_a, pair_b, areas = [], [], []
    for g in np.argsort(cut[starts], kind="stable"):   # cut[starts]: each plane's first face
        # a piece lies wholly on one side of the plane, so its vertex mean tells the side
        lower = starts[g] + np.flatnonzero(below[starts[g]:ends[g]])
        upper = starts[g] + np.flatnonzero(~below[starts[g]:ends[g]])
        if not len(lower) or not len(upper):
            continue
        pairs = shapely.STRtree(boxes[upper]).query(boxes[lower])
        pairs = pairs[:, np.lexsort((pairs[1], pairs[0]))]
        a, b = lower[pairs[0]], upper[pairs[1]]
        shared = np.empty(len(a))
        clip_convex_pairs(uv, ring_start, a, b, tol_m, shared)
        keep = shared > min_area_m2
        pair_a.append(a[keep])
        pair_b.append(b[keep])
        areas.append(shared[keep])
    if not pair_a:
        return empty
    a, b, area = np.concatenate(pair_a), np.concatenate(pair_b), np.concatenate(areas)
    j = plane_of[a]
    rows = np.stack([face_piece[cut[a]], face_piece[cut[b]], j], axis=1).astype(np.int64)
    real = np.where(planes.label[j] < 0, 0.0, area)     # a tunnel wall: fictitious between rock pieces
    disk = np.flatnonzero(np.isfinite(planes.radius_m[j]) & (planes.label[j] >= 0))
    if len(disk):
        jd = j[disk]
        centre_uv = np.stack([np.einsum("ij,ij->i", planes.centre_m[jd], e1[jd]),
                              np.einsum("ij,ij->i", planes.centre_m[jd], e2[jd])], axis=1)
        overlap = np.empty(len(disk))
        disk_overlap(uv, ring_start, a[disk], b[disk], centre_uv, planes.radius_m[jd].astype(np.float64),
                     DISK_POLYGON_VERTICES, tol_m, overlap)
        real[disk] = overlap
    return rows, area, real


def _plane_bases(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~rockmass.blockgen.polyhedra.plane_basis` of every row of ``normal (n, 3)``."""
    nx, ny, nz = np.asarray(normal, float).T
    first = np.abs(nx) < 0.9
    with np.errstate(divide="ignore", invalid="ignore"):
        e1 = np.where(first[:, None], np.stack([np.zeros_like(nx), -nz, ny], axis=1) / np.hypot(ny, nz)[:, None],
                      np.stack([nz, np.zeros_like(nx), -nx], axis=1) / np.hypot(nx, nz)[:, None])
    return e1, np.cross(normal, e1)


def _components(n: int, links: np.ndarray, area: np.ndarray, real: np.ndarray,
                excavated: np.ndarray) -> np.ndarray:
    """In-situ block of each rock piece (−1 for excavated ones): rock pieces joined by any link with
    a fictitious part are one block."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    a, b = links[:, 0], links[:, 1]
    joined = (real < area * (1.0 - 1e-9)) & ~excavated[a] & ~excavated[b]
    graph = coo_matrix((np.ones(int(joined.sum())), (a[joined], b[joined])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    rock = ~excavated
    block_id = np.full(n, -1, np.int64)
    block_id[rock] = np.unique(labels[rock], return_inverse=True)[1]
    return block_id
