"""Convex polyhedra cut exactly by planes: the geometric core of 3D block models.

A block is a convex polyhedron held as its boundary: a tuple of planar convex faces, each a ``(k, 3)``
array of vertices in metres, counter-clockwise seen from outside, and one integer label per face
saying where the face came from (``>= 0``: the fracture or joint plane that made it; negative: the
domain box, :data:`LABEL_BOX`).

Cutting a block by the plane n·x = d (docs/blocks.md §8) splits every face by the signed distance
s = n·x − d of its vertices (one step of Sutherland–Hodgman clipping on each side), and closes both
pieces with the *cap*: the polygon through the points where the plane meets the block's edges,
ordered by angle about the plane normal. Vertices with |s| ≤ ``tol_m`` count as on the plane, so a
plane through a vertex, along an edge or along a face never makes a piece of zero volume: a block
that lies on one side of the plane within ``tol_m`` is not cut.

Volume and centroid follow from the divergence theorem on the fan triangles of the faces:
V = Σ_t (a_t − p)·((b_t − p) × (c_t − p)) / 6 with any reference point p, and the centroid is the
volume-weighted mean of the tetrahedra's centroids (p + a_t + b_t + c_t)/4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Polyhedron", "LABEL_BOX", "box_polyhedron", "split", "plane_basis", "polygon_area_3d"]

#: face label of the six faces of the domain box.
LABEL_BOX = -1


@dataclass(frozen=True)
class Polyhedron:
    """A convex polyhedron: ``faces`` (each ``(k, 3)``, counter-clockwise from outside) and one
    ``labels`` entry (int) per face."""

    faces: tuple[np.ndarray, ...]
    labels: tuple[int, ...]

    def _fan(self) -> tuple[np.ndarray, np.ndarray]:
        """Reference point p and the fan triangles ``(t, 3, 3)`` of all faces."""
        tris = [np.stack([np.broadcast_to(f[0], (len(f) - 2, 3)), f[1:-1], f[2:]], axis=1)
                for f in self.faces]
        return self.faces[0][0], np.concatenate(tris)

    def volume_m3(self) -> float:
        """V = Σ (a − p)·((b − p) × (c − p)) / 6 over the fan triangles (divergence theorem)."""
        p, t = self._fan()
        a, b, c = t[:, 0] - p, t[:, 1] - p, t[:, 2] - p
        return float(np.einsum("ij,ij->", a, np.cross(b, c)) / 6.0)

    def centroid_m(self) -> np.ndarray:
        """Volume-weighted mean of the fan tetrahedra's centroids (p + a + b + c)/4."""
        p, t = self._fan()
        a, b, c = t[:, 0] - p, t[:, 1] - p, t[:, 2] - p
        v = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
        return p + (v[:, None] * (a + b + c)).sum(axis=0) / (4.0 * v.sum())

    def moments(self) -> tuple[float, np.ndarray, np.ndarray]:
        """Volume V, first moment ∫x dV (3,) and second moment ∫x xᵀ dV (3, 3) about the origin.

        Per fan tetrahedron (p, a, b, c) of volume v: ∫x dV = v (p + a + b + c)/4 and
        ∫x xᵀ dV = v/20 (Σ_k x_k x_kᵀ + (Σ_k x_k)(Σ_k x_k)ᵀ) over its four vertices x_k (the
        exact second moment of a tetrahedron; e.g. Tonon 2005).
        """
        p, t = self._fan()
        a, b, c = t[:, 0] - p, t[:, 1] - p, t[:, 2] - p
        v = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
        corners = np.stack([np.broadcast_to(p, a.shape), t[:, 0], t[:, 1], t[:, 2]], axis=1)
        total = corners.sum(axis=1)
        second = (np.einsum("tki,tkj->tij", corners, corners) + np.einsum("ti,tj->tij", total, total))
        return float(v.sum()), (v[:, None] * total).sum(axis=0) / 4.0, (v[:, None, None] * second).sum(axis=0) / 20.0

    def surface_area_m2(self) -> float:
        """Σ of the face areas."""
        return sum(polygon_area_3d(f) for f in self.faces)

    def vertices_m(self) -> np.ndarray:
        """Every face vertex, stacked (a vertex shared by k faces appears k times)."""
        return np.concatenate(self.faces)


def box_polyhedron(box_m) -> Polyhedron:
    """The box ``[[x0, y0, z0], [x1, y1, z1]]`` as a polyhedron with six faces labelled
    :data:`LABEL_BOX`.

    >>> round(box_polyhedron([[0, 0, 0], [1, 2, 3]]).volume_m3(), 12)
    6.0
    """
    (x0, y0, z0), (x1, y1, z1) = np.asarray(box_m, float)
    corner = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                       [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])
    rings = ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))
    return Polyhedron(tuple(corner[list(r)] for r in rings), (LABEL_BOX,) * 6)


def plane_basis(normal) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors e1, e2 with (e1, e2, n) right-handed and orthonormal, for one unit normal n."""
    nx, ny, nz = (float(v) for v in normal)
    if abs(nx) < 0.9:           # e1 = x̂ × n, normalised
        e1 = np.array([0.0, -nz, ny]) / math.hypot(ny, nz)
    else:                       # e1 = ŷ × n, normalised
        e1 = np.array([nz, 0.0, -nx]) / math.hypot(nx, nz)
    e2 = np.array([ny * e1[2] - nz * e1[1], nz * e1[0] - nx * e1[2], nx * e1[1] - ny * e1[0]])
    return e1, e2


def polygon_area_3d(ring: np.ndarray) -> float:
    """Area of a planar polygon in 3D: half the norm of Σ v_i × v_{i+1}."""
    return 0.5 * float(np.linalg.norm(np.cross(ring, np.roll(ring, -1, axis=0)).sum(axis=0)))


def _clip_face(face: np.ndarray, s: np.ndarray, tol_m: float):
    """The parts of one face with s ≤ 0 and s ≥ 0, and the points of the face on the plane.

    A part is returned only when the face has a vertex strictly on that side (|s| > ``tol_m``).
    """
    below, above, on = [], [], []
    k = len(face)
    for i in range(k):
        p, q, sp, sq = face[i], face[(i + 1) % k], s[i], s[(i + 1) % k]
        if sp <= tol_m:
            below.append(p)
        if sp >= -tol_m:
            above.append(p)
        if abs(sp) <= tol_m:
            on.append(p)
        if (sp < -tol_m and sq > tol_m) or (sp > tol_m and sq < -tol_m):
            x = p + (sp / (sp - sq)) * (q - p)
            below.append(x)
            above.append(x)
            on.append(x)
    lower = np.array(below) if (s < -tol_m).any() else None
    upper = np.array(above) if (s > tol_m).any() else None
    return lower, upper, on


def _cap(points: list, normal: np.ndarray, tol_m: float) -> np.ndarray | None:
    """The convex polygon through ``points`` (on the plane), counter-clockwise about ``normal``;
    points closer than ``tol_m`` merged. None when fewer than three distinct points remain."""
    pts = np.asarray(points)
    e1, e2 = plane_basis(normal)
    uv = np.stack([pts @ e1, pts @ e2], axis=1)
    angle = np.arctan2(*(uv - uv.mean(axis=0)).T[::-1])
    pts = pts[np.argsort(angle, kind="stable")]
    keep = [pts[0]]
    for p in pts[1:]:
        if np.linalg.norm(p - keep[-1]) > tol_m:
            keep.append(p)
    if len(keep) > 1 and np.linalg.norm(keep[-1] - keep[0]) <= tol_m:
        keep.pop()
    return np.array(keep) if len(keep) >= 3 else None


def split(block: Polyhedron, normal, offset_m: float, label: int,
          tol_m: float) -> tuple[Polyhedron | None, Polyhedron | None, np.ndarray | None]:
    """Cut ``block`` by the plane n·x = ``offset_m``.

    Returns ``(below, above, cap)``: the pieces with n·x ≤ d and n·x ≥ d, and the cap polygon
    (counter-clockwise about n, i.e. as the outward face of ``below``). When the block lies on one
    side within ``tol_m`` it comes back whole on that side, with ``None`` for the other and the cap.
    The cap is labelled ``label`` in both pieces.

    >>> below, above, cap = split(box_polyhedron([[0, 0, 0], [1, 1, 1]]), [0, 0, 1], 0.25, 7, 1e-12)
    >>> round(below.volume_m3(), 12), round(above.volume_m3(), 12), below.labels.count(7)
    (0.25, 0.75, 1)
    """
    n = np.asarray(normal, float)
    distances = [f @ n - offset_m for f in block.faces]
    lowest = min(float(d.min()) for d in distances)
    highest = max(float(d.max()) for d in distances)
    if highest <= tol_m:
        return block, None, None
    if lowest >= -tol_m:
        return None, block, None
    lower_faces, lower_labels, upper_faces, upper_labels, on = [], [], [], [], []
    for face, s, face_label in zip(block.faces, distances, block.labels):
        lower, upper, points = _clip_face(face, s, tol_m)
        on.extend(points)
        if lower is not None and len(lower) >= 3:
            lower_faces.append(lower)
            lower_labels.append(face_label)
        if upper is not None and len(upper) >= 3:
            upper_faces.append(upper)
            upper_labels.append(face_label)
    cap = _cap(on, n, tol_m)
    if cap is None or polygon_area_3d(cap) <= tol_m * tol_m:
        # the plane only grazes the block: keep it whole on the side of its larger part
        return (block, None, None) if -lowest >= highest else (None, block, None)
    below = Polyhedron(tuple(lower_faces) + (cap,), tuple(lower_labels) + (int(label),))
    above = Polyhedron(tuple(upper_faces) + (cap[::-1].copy(),), tuple(upper_labels) + (int(label),))
    return below, above, cap



def _to_flat(pieces) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Polyhedra → the flat layout of :mod:`rockmass.blockgen._polyhedra_kernels`: ``verts (v, 3)``
    float64, ``face_start (f + 1,)``, ``face_label (f,)`` and ``piece_start (n + 1,)`` int64."""
    faces = [face for piece in pieces for face in piece.faces]
    face_start = np.zeros(len(faces) + 1, np.int64)
    np.cumsum([len(face) for face in faces], out=face_start[1:])
    piece_start = np.zeros(len(pieces) + 1, np.int64)
    np.cumsum([len(piece.faces) for piece in pieces], out=piece_start[1:])
    labels = np.array([label for piece in pieces for label in piece.labels], np.int64)
    verts = np.ascontiguousarray(np.concatenate(faces) if faces else np.zeros((0, 3)), dtype=np.float64)
    return verts, face_start, labels, piece_start


def _from_flat(verts: np.ndarray, face_start: np.ndarray, face_label: np.ndarray,
               piece_start: np.ndarray) -> list[Polyhedron]:
    """The flat layout → polyhedra whose faces are views into ``verts``."""
    starts = face_start.tolist()
    faces = [verts[a:b] for a, b in zip(starts[:-1], starts[1:])]
    labels = face_label.tolist()
    bounds = piece_start.tolist()
    return [Polyhedron(tuple(faces[a:b]), tuple(labels[a:b])) for a, b in zip(bounds[:-1], bounds[1:])]
