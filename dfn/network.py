"""Three-dimensional disk fracture networks: the :class:`DiskNetwork` type and its intensities.

A network is a structure of arrays (one numpy array per field) in the world frame x = East, y = North, z = Up,
metres: ``centre_m (n, 3)``, unit ``normal (n, 3)`` (upper normals, n_z >= 0), ``radius_m (n,)`` and
``set_id (n,) int64``, plus the domain box ``domain_m`` = ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``
that the network was generated for.

Intensities (docs/fractures.md §5, §11.1) are one-sided: P32 = Σ (area of each disk inside the box) / V, and
P30 = (number of disk centres inside the box) / V.

Clipped area
------------
A disk that lies wholly inside the box (its extent along axis k is r sqrt(1 - n_k²) on both sides of
the centre) contributes its exact area π r²; a disk wholly outside along one axis contributes 0.
A disk cut by a face of the box is approximated by the regular ``n_vertices``-gon inscribed in it,
clipped by the six planes of the box (Sutherland-Hodgman), and the clipped polygon's area is scaled
by π / (m/2 · sin(2π/m)) (disk area / polygon area, m = n_vertices), which makes the part of the
disk away from the box faces exact. The remaining error comes from the polygon edges near the box
faces only: it is at most the disk-minus-polygon area, 1 - (m/2π) sin(2π/m) ≈ (2π/m)²/6 of πr²
(0.16 % for m = 64, the default) and usually much less, per cut disk.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .orientation import _as_float_array, _as_scalar

__all__ = ["DiskNetwork", "disk_basis", "as_box"]

#: Default polygon resolution for clipped areas (error bound 0.16 % of a cut disk's area).
CLIP_VERTICES = 64


def as_box(box: ArrayLike, name: str = "domain_m") -> np.ndarray:
    """A box as a new ``(2, 3)`` float64 array ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``.

    Accepts that shape or the flat ``(xmin, ymin, zmin, xmax, ymax, zmax)``; every max must exceed
    its min (the message names ``name``).
    """
    array = _as_float_array(box, name)
    if array.shape == (6,):
        array = array.reshape(2, 3)
    if array.shape != (2, 3):
        raise ValueError(f"{name} must be [[xmin, ymin, zmin], [xmax, ymax, zmax]] (shape (2, 3)) or "
                         f"six numbers, got shape {array.shape}")
    bad = ~(array[1] > array[0])
    if bad.any():
        axes = [a for a, b in zip("xyz", bad) if b]
        raise ValueError(f"{name}: max must be > min on every axis, not on {', '.join(axes)} "
                         f"(got min {array[0].tolist()}, max {array[1].tolist()})")
    return array.copy()


def disk_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two ``(n, 3)`` unit vectors e1, e2 with (e1, e2, normal) right-handed and orthonormal.

    Vectorised form of the branch-free basis of Duff et al. (2017), as in
    :func:`rockmass.dfn.fisher.sample_fisher`; ``normal`` must hold unit rows.
    """
    x, y, z = normal[:, 0], normal[:, 1], normal[:, 2]
    sign = np.where(z >= 0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    e1 = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=1)
    e2 = np.stack([b, sign + y * y * a, -y], axis=1)
    return e1, e2


def _require_network(network: object) -> None:
    """TypeError unless ``network`` is a :class:`DiskNetwork` (shared by the samplers and writers)."""
    if not isinstance(network, DiskNetwork):
        raise TypeError(f"network must be a DiskNetwork, got {type(network).__name__}")


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class DiskNetwork:
    """Circular fractures (disks) in 3D with the domain box they were generated for.

    Parameters
    ----------
    centre_m : (n, 3) array_like of float
        Disk centres (x East, y North, z Up) in metres.
    normal : (n, 3) array_like of float
        Disk normals, any non-zero length: stored normalised and turned to the upper hemisphere
        (n_z >= 0; a horizontal normal is kept as given).
    radius_m : (n,) array_like of float
        Radii in metres, > 0.
    set_id : (n,) array_like of int
        Fracture set of each disk, >= 0.
    domain_m : (2, 3) or (6,) array_like of float
        The domain box ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` in metres.

    Notes
    -----
    Arrays are copied and made read-only; the caller's inputs are never modified.

    Examples
    --------
    >>> net = DiskNetwork([[5, 5, 5]], [[0, 0, 2]], [1.0], [0], [0, 0, 0, 10, 10, 10])
    >>> round(net.p32(), 6)   # π / 1000
    0.003142
    """

    centre_m: np.ndarray
    normal: np.ndarray
    radius_m: np.ndarray
    set_id: np.ndarray
    domain_m: np.ndarray

    def __post_init__(self) -> None:
        centre = _as_float_array(self.centre_m, "centre_m").reshape(-1, 3) \
            if np.size(self.centre_m) == 0 else _as_float_array(self.centre_m, "centre_m")
        if centre.ndim != 2 or centre.shape[1] != 3:
            raise ValueError(f"centre_m must have shape (n, 3), got {centre.shape}")
        n = centre.shape[0]
        normal = _as_float_array(self.normal, "normal").reshape(-1, 3) if n == 0 \
            else _as_float_array(self.normal, "normal")
        if normal.shape != (n, 3):
            raise ValueError(f"normal must have shape ({n}, 3) like centre_m, got {normal.shape}")
        length = np.linalg.norm(normal, axis=1)
        zero = np.flatnonzero(length == 0)
        if zero.size:
            raise ValueError(f"normal must be non-zero vectors; rows {zero[:10].tolist()} are zero")
        off = np.abs(length - 1.0) > 4.0 * np.finfo(np.float64).eps  # unit rows kept bit for bit
        normal = np.where(off[:, None], normal / length[:, None], normal)
        normal = np.where((normal[:, 2] < 0)[:, None], -normal, normal)
        radius = _as_float_array(self.radius_m, "radius_m").reshape(-1)
        if radius.shape != (n,):
            raise ValueError(f"radius_m must have shape ({n},), got {radius.shape}")
        if (radius <= 0).any():
            bad = np.flatnonzero(radius <= 0)
            raise ValueError(f"radius_m must be > 0 (disk radius in metres); rows {bad[:10].tolist()} "
                             f"are {radius[bad[:10]].tolist()}")
        set_array = np.asarray(self.set_id)
        if set_array.size == 0:
            set_array = set_array.astype(np.int64).reshape(-1)
        if set_array.dtype.kind not in "iu":
            raise TypeError(f"set_id must hold integers, got dtype {set_array.dtype}")
        set_array = set_array.astype(np.int64).reshape(-1)
        if set_array.shape != (n,):
            raise ValueError(f"set_id must have shape ({n},), got {set_array.shape}")
        if (set_array < 0).any():
            raise ValueError("set_id must be >= 0")
        box = as_box(self.domain_m)
        for name, value in (("centre_m", centre), ("normal", normal), ("radius_m", radius),
                            ("set_id", set_array), ("domain_m", box)):
            object.__setattr__(self, name, _read_only(np.array(value, copy=True)))

    # -- sizes --------------------------------------------------------------------------------

    @property
    def n_fractures(self) -> int:
        """Number of disks."""
        return int(self.radius_m.shape[0])

    @property
    def volume_m3(self) -> float:
        """Volume of the domain box in m³."""
        return float(np.prod(self.domain_m[1] - self.domain_m[0]))

    def __len__(self) -> int:
        return self.n_fractures

    def area_m2(self) -> np.ndarray:
        """One-sided area π r² of each disk, ``(n,)`` float64 in m²."""
        return np.pi * self.radius_m ** 2

    def subset(self, selection: ArrayLike) -> DiskNetwork:
        """The disks selected by a boolean mask or index array, same domain."""
        sel = np.asarray(selection)
        return DiskNetwork(self.centre_m[sel], self.normal[sel], self.radius_m[sel], self.set_id[sel],
                           self.domain_m)

    def clipped_area_m2(self, box: ArrayLike | None = None, *, n_vertices: int = CLIP_VERTICES) -> np.ndarray:
        """One-sided area of each disk inside ``box`` (default: the domain), ``(n,)`` float64 in m².

        Exact for disks wholly inside or outside; disks cut by the box faces use the scaled clipped
        ``n_vertices``-gon of the module docstring (relative error per cut disk below
        (2π/m)²/6).
        """
        b = self.domain_m if box is None else as_box(box, "box")
        m = int(_as_scalar(n_vertices, "n_vertices", low=3))
        return clipped_disk_areas(self.centre_m, self.normal, self.radius_m, b, n_vertices=m)

    def _select(self, set_id: int | None) -> np.ndarray:
        return np.ones(self.n_fractures, bool) if set_id is None else self.set_id == set_id

    def p32(self, set_id: int | None = None, box: ArrayLike | None = None) -> float:
        """Achieved one-sided P32 (m²/m³) in ``box`` (default the domain), of one set or all."""
        b = self.domain_m if box is None else as_box(box, "box")
        sel = self._select(set_id)
        area = clipped_disk_areas(self.centre_m[sel], self.normal[sel], self.radius_m[sel], b)
        return float(area.sum() / np.prod(b[1] - b[0]))

    def p30(self, set_id: int | None = None, box: ArrayLike | None = None) -> float:
        """Disk centres per m³ inside ``box`` (default the domain), of one set or all."""
        b = self.domain_m if box is None else as_box(box, "box")
        sel = self._select(set_id)
        c = self.centre_m[sel]
        inside = np.all((c >= b[0]) & (c <= b[1]), axis=1)
        return float(inside.sum() / np.prod(b[1] - b[0]))

    def __repr__(self) -> str:
        sets = np.unique(self.set_id).tolist()
        return (f"DiskNetwork({self.n_fractures} disks, sets {sets}, domain "
                f"{self.domain_m[0].tolist()}..{self.domain_m[1].tolist()} m)")


def clipped_disk_areas(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, box: np.ndarray,
                       *, n_vertices: int = CLIP_VERTICES) -> np.ndarray:
    """Area inside ``box`` of each disk (validated arrays; see :meth:`DiskNetwork.clipped_area_m2`)."""
    n = radius.shape[0]
    out = np.zeros(n)
    if n == 0:
        return out
    extent = radius[:, None] * np.sqrt(np.clip(1.0 - normal ** 2, 0.0, 1.0))  # half-extent per axis
    lo = centre - extent
    hi = centre + extent
    inside = np.all((lo >= box[0]) & (hi <= box[1]), axis=1)
    outside = np.any((hi <= box[0]) | (lo >= box[1]), axis=1)
    out[inside] = np.pi * radius[inside] ** 2
    cut = np.flatnonzero(~inside & ~outside)
    if cut.size:
        from ._clip_kernels import clipped_polygon_areas  # numba: loaded only when a disk is cut

        f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731 (one signature)
        c = f64(centre[cut])
        nn = f64(normal[cut])
        e1, e2 = disk_basis(nn)
        part = np.empty(cut.size)
        clipped_polygon_areas(c, f64(e1), f64(e2), f64(radius[cut]), f64(box[0]), f64(box[1]),
                              np.int64(n_vertices), part)
        m = n_vertices
        out[cut] = part * (np.pi / (0.5 * m * np.sin(2.0 * np.pi / m)))  # polygon -> disk area
    return out
