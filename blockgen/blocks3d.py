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
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely

from .polyhedra import Polyhedron, box_polyhedron, plane_basis, split

if TYPE_CHECKING:
    from .openings3d import Tunnel

__all__ = ["Planes", "BlockSet3D", "persistent_set_planes", "disk_planes", "cut_box"]

#: vertices of the polygon standing for a disk in real-area computations.
DISK_POLYGON_VERTICES = 256
#: length tolerance / box diagonal.
TOL_FRACTION = 1e-10


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
    box = np.asarray(box_m, float)
    size = float(np.linalg.norm(box[1] - box[0]))
    tol = TOL_FRACTION * size if tol_m is None else float(tol_m)
    walls = [t.wall_planes(label=-2 - k) for k, t in enumerate(tunnels)]
    all_planes = _join(*planes, *walls) if planes or walls else None
    pieces = [box_polyhedron(box)]
    bounds = [box[:1].copy(), box[1:].copy()]
    first_wall = sum(len(p) for p in planes)
    for j in range(first_wall):
        _cut_by_plane(pieces, bounds, all_planes, j, tol, inside=None)
    j = first_wall
    for tunnel, wall in zip(tunnels, walls):
        for _ in range(len(wall)):
            _cut_by_plane(pieces, bounds, all_planes, j, tol, inside=tunnel)
            j += 1
    excavated = np.array([any(t.contains(p.vertices_m(), tol) for t in tunnels) for p in pieces], bool)
    moments = [p.moments() for p in pieces]
    volume = np.array([m[0] for m in moments])
    centroid = np.array([m[1] for m in moments]) / volume[:, None]
    links, area, real = _links(pieces, all_planes, tol * size)
    block_id = _components(len(pieces), links, area, real, excavated)
    return BlockSet3D(tuple(pieces), volume, centroid, block_id, links, area, real, box, excavated,
                      all_planes)


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


def _links(pieces, planes: Planes | None, min_area_m2: float):
    """Pairs of pieces sharing part of a cut: (a, b, plane index), shared area, real area.

    Faces carry the index of the plane that made them; on each plane the faces whose outward normal
    is +n (their piece lies below) are matched with those facing −n by polygon overlap in the plane.
    """
    if planes is None:
        return np.zeros((0, 3), np.int64), np.zeros(0), np.zeros(0)
    faces_by_plane: dict[int, list] = {}
    for p, piece in enumerate(pieces):
        for face, j in zip(piece.faces, piece.labels):
            if j >= 0:
                faces_by_plane.setdefault(j, []).append((p, face))
    means = [piece.vertices_m().mean(axis=0) for piece in pieces]
    rows, areas, reals = [], [], []
    for j, faces in faces_by_plane.items():
        n, e = planes.normal[j], plane_basis(planes.normal[j])
        owner = np.array([p for p, _ in faces])
        polygons = np.array([shapely.Polygon(np.stack([f @ e[0], f @ e[1]], axis=1)) for _, f in faces])
        # a piece lies wholly on one side of the plane, so its vertex mean tells the side
        below = np.array([means[p] @ n for p, _ in faces]) < planes.offset_m[j]
        lower, upper = np.flatnonzero(below), np.flatnonzero(~below)
        if not len(lower) or not len(upper):
            continue
        pairs = shapely.STRtree(polygons[upper]).query(polygons[lower], predicate="intersects")
        a, b = lower[pairs[0]], upper[pairs[1]]
        shared = shapely.intersection(polygons[a], polygons[b])
        area = shapely.area(shared)
        keep = area > min_area_m2
        a, b, shared, area = a[keep], b[keep], shared[keep], area[keep]
        rows.append(np.stack([owner[a], owner[b], np.full(len(a), j)], axis=1))
        areas.append(area)
        if planes.label[j] < 0:      # a tunnel wall: fictitious between rock pieces
            reals.append(np.zeros(len(area)))
        else:
            reals.append(_real_area(shared, area, planes.centre_m[j] @ np.stack(e).T, planes.radius_m[j]))
    if not rows:
        return np.zeros((0, 3), np.int64), np.zeros(0), np.zeros(0)
    return np.concatenate(rows).astype(np.int64), np.concatenate(areas), np.concatenate(reals)


def _real_area(shared: np.ndarray, area: np.ndarray, centre_uv: np.ndarray, radius: float) -> np.ndarray:
    """Fractured part of each shared polygon: all of it when every vertex lies within the disk
    (exact: polygon and disk are convex), else its overlap with a 256-gon of the disk."""
    real = area.copy()
    if not math.isfinite(radius):
        return real
    xy, owner = shapely.get_coordinates(shared, return_index=True)
    outside = np.bincount(owner, weights=np.hypot(*(xy - centre_uv).T) > radius, minlength=len(shared)) > 0
    if outside.any():
        disk = shapely.Point(centre_uv).buffer(radius, quad_segs=DISK_POLYGON_VERTICES // 4)
        real[outside] = shapely.area(shapely.intersection(shared[outside], disk))
    return real


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
