"""Virtual sampling of a disk network: scanlines (intersections, P10, spacings) and planes (traces).

Plane frame
-----------
A sampling plane through ``point`` o with unit normal m gets the in-plane frame (u, v, m),
right-handed, origin at o (:func:`plane_frame`):

- u = (ẑ × m) / |ẑ × m| — horizontal, to the *right* of a viewer who looks at the plane against m
  (m points from the plane towards the viewer, like the outward normal of a rock face); for a face
  whose normal points North (m = +y) u points West;
- v = m × u — up the plane's line of greatest slope (v = +z on a vertical plane);
- a horizontal plane (|m_z| > 1 - 1e-12) uses u = +x (East) and v = m × u (North when m = +z:
  map view).

A point p in 3D has plane coordinates (u, v) = ((p - o)·u, (p - o)·v). The window polygon and the
traces of :func:`sample_plane` are in metres in this frame (``TraceMap.frame == "plane"``).

Traces
------
Disk (c, n, r) and plane (o, m): with s = m·(c - o), cos ψ = n·m and sin ψ = |n × m|, the disk is cut
iff |s| < r sin ψ; the trace is the chord through q = c - s (m - cos ψ n) / sin²ψ along d = n × m / sin ψ,
of half-length sqrt(r² - s²/sin²ψ). Disks parallel to the plane (sin ψ < 1e-12) leave no trace.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike

from .network import DiskNetwork, _require_network
from .orientation import _as_float_array, _as_vectors
from .tracemap import TraceMap

__all__ = ["LineSample", "plane_frame", "sample_line", "sample_plane"]

#: sin ψ below which a disk counts as parallel to the sampling plane (no trace).
PARALLEL_SIN = 1e-12


def _point(value: ArrayLike, name: str) -> np.ndarray:
    array = _as_float_array(value, name)
    if array.shape != (3,):
        raise ValueError(f"{name} must be one point (x, y, z) in metres, shape (3,), got {array.shape}")
    return array


@dataclass(frozen=True, eq=False)
class LineSample:
    """Intersections of a scanline with a disk network.

    Attributes
    ----------
    position_m : (k,) float64
        Distance of each intersection from the line's start, sorted ascending, metres.
    set_id, disk_index : (k,) int64
        Set of the disk hit, and its row in the network.
    length_m : float
        Scanline length.
    direction : (3,) float64
        Unit direction from start to end.
    """

    position_m: np.ndarray
    set_id: np.ndarray
    disk_index: np.ndarray
    length_m: float
    direction: np.ndarray

    @property
    def n_hits(self) -> int:
        return int(self.position_m.size)

    def p10(self, set_id: int | None = None) -> float:
        """Intersections per metre (1/m), of one set or all."""
        hits = self.n_hits if set_id is None else int(np.sum(self.set_id == set_id))
        return hits / self.length_m

    def spacings_m(self, set_id: int | None = None) -> np.ndarray:
        """Distances between consecutive intersections along the line (of one set or all), metres."""
        pos = self.position_m if set_id is None else self.position_m[self.set_id == set_id]
        return np.diff(pos)


def sample_line(network: DiskNetwork, start: ArrayLike, end: ArrayLike) -> LineSample:
    """Intersect the segment from ``start`` to ``end`` with every disk of ``network``.

    Parameters
    ----------
    network : DiskNetwork
    start, end : (3,) array_like of float
        End points (x, y, z) of the scanline in metres, distinct.

    Returns
    -------
    LineSample
        Hits sorted by distance from ``start``. P10 of a Poisson network is P32 / C13 in expectation
        (docs/fractures.md §12.3, eq. (7.1); Wang 2005), and for a stationary network hit counts are Poisson.

    Examples
    --------
    >>> net = DiskNetwork([[0, 0, 1], [0, 0, 3]], [[0, 0, 1]] * 2, [1.0, 1.0], [0, 1], [-5, -5, 0, 5, 5, 5])
    >>> hits = sample_line(net, [0, 0, 0], [0, 0, 4])
    >>> hits.position_m.tolist(), hits.set_id.tolist(), hits.p10()
    ([1.0, 3.0], [0, 1], 0.5)
    """
    _require_network(network)
    a = _point(start, "start")
    b = _point(end, "end")
    vec = b - a
    length = float(np.linalg.norm(vec))
    if length == 0:
        raise ValueError("start and end must differ (scanline of zero length)")
    direction = vec / length
    n = network.normal
    denom = n @ direction
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("ij,ij->i", network.centre_m - a, n) / denom
    ok = (denom != 0) & (t >= 0) & (t <= length)
    idx = np.flatnonzero(ok)
    foot = a + t[idx, None] * direction
    dist2 = np.sum((foot - network.centre_m[idx]) ** 2, axis=1)
    idx = idx[dist2 <= network.radius_m[idx] ** 2]
    order = np.argsort(t[idx], kind="stable")
    idx = idx[order]
    return LineSample(t[idx].copy(), network.set_id[idx].copy(), idx.astype(np.int64), length, direction)


def plane_frame(normal: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (u, v, m) of a sampling plane's frame (module docstring), each (3,).

    Examples
    --------
    >>> u, v, m = plane_frame([0, 1, 0])     # a face looking North
    >>> u.tolist(), v.tolist()
    ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    """
    m = _as_vectors(normal, "normal")
    if m.shape != (3,):
        raise ValueError(f"normal must be one vector of shape (3,), got {m.shape}")
    if abs(m[2]) > 1.0 - 1e-12:
        u = np.array([1.0, 0.0, 0.0])
    else:
        u = np.cross([0.0, 0.0, 1.0], m)
        u /= np.linalg.norm(u)
    v = np.cross(m, u)
    return u, v + 0.0, m


def _window(window_uv_m: ArrayLike) -> shapely.Polygon:
    if isinstance(window_uv_m, shapely.Polygon):
        polygon = window_uv_m
    else:
        ring = _as_float_array(window_uv_m, "window_uv_m")
        if ring.ndim != 2 or ring.shape[1] != 2 or ring.shape[0] < 3:
            raise ValueError(f"window_uv_m must be a polygon ring of shape (k, 2), k >= 3, got {ring.shape}")
        polygon = shapely.Polygon(ring)
    if not polygon.is_valid or polygon.area <= 0:
        raise ValueError("window_uv_m must be a valid polygon of non-zero area (no self-intersection)")
    return shapely.orient_polygons(polygon) if hasattr(shapely, "orient_polygons") \
        else shapely.geometry.polygon.orient(polygon, 1.0)


def _clip_convex(seg: np.ndarray, ring: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cyrus-Beck: clip (k, 4) segments by a counter-clockwise convex ring; (kept mask, clipped)."""
    p0, p1 = seg[:, :2], seg[:, 2:]
    dp = p1 - p0
    t_in = np.zeros(seg.shape[0])
    t_out = np.ones(seg.shape[0])
    keep = np.ones(seg.shape[0], bool)
    for k in range(ring.shape[0]):
        a, b = ring[k], ring[(k + 1) % ring.shape[0]]
        inward = np.array([-(b[1] - a[1]), b[0] - a[0]])  # left normal of a CCW edge
        num = (p0 - a) @ inward
        den = dp @ inward
        parallel = den == 0
        keep &= ~(parallel & (num < 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -num / den
        t_in = np.where(~parallel & (den > 0), np.maximum(t_in, t), t_in)
        t_out = np.where(~parallel & (den < 0), np.minimum(t_out, t), t_out)
    keep &= t_in < t_out
    clipped = np.concatenate([p0 + t_in[:, None] * dp, p0 + t_out[:, None] * dp], axis=1)
    return keep, clipped


def _plane_traces(centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, set_id: np.ndarray,
                  origin: np.ndarray, frame: tuple, polygon: shapely.Polygon) -> TraceMap:
    """Traces of validated disks on the plane (origin, frame), clipped to ``polygon`` (u, v)."""
    u, v, m = frame
    s = (centre - origin) @ m
    cos = normal @ m
    sin = np.sqrt(np.clip(1.0 - cos ** 2, 0.0, 1.0))
    cut = np.flatnonzero((sin > PARALLEL_SIN) & (np.abs(s) < radius * sin))
    s, cos, sin = s[cut], cos[cut], sin[cut]
    n = normal[cut]
    w = m - cos[:, None] * n
    q = centre[cut] - (s / sin ** 2)[:, None] * w
    d = np.cross(n, m) / sin[:, None]
    half = np.sqrt(np.maximum(radius[cut] ** 2 - (s / sin) ** 2, 0.0))
    qu, qv = (q - origin) @ u, (q - origin) @ v
    du, dv = d @ u, d @ v
    seg = np.stack([qu - half * du, qv - half * dv, qu + half * du, qv + half * dv], axis=1)
    umin, vmin, umax, vmax = polygon.bounds
    near = ((np.maximum(seg[:, 0], seg[:, 2]) >= umin) & (np.minimum(seg[:, 0], seg[:, 2]) <= umax)
            & (np.maximum(seg[:, 1], seg[:, 3]) >= vmin) & (np.minimum(seg[:, 1], seg[:, 3]) <= vmax))
    seg, cut = seg[near], cut[near]
    ring = np.asarray(polygon.exterior.coords)[:-1]
    window = ring.copy()
    if abs(polygon.convex_hull.area - polygon.area) <= 1e-12 * polygon.area:
        keep, clipped = _clip_convex(seg, ring)
        return TraceMap.from_segments(clipped[keep], {"set": set_id[cut[keep]], "disk": cut[keep]},
                                      window=window, frame="plane")
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    pieces = shapely.intersection(lines, polygon)
    parts, owner = shapely.get_parts(pieces, return_index=True)
    line_parts = shapely.get_type_id(parts) == shapely.GeometryType.LINESTRING
    parts, owner = parts[line_parts], owner[line_parts]
    positive = shapely.length(parts) > 0
    parts, owner = parts[positive], owner[positive]
    return TraceMap.from_shapely(parts, {"set": set_id[cut[owner]], "disk": cut[owner]},
                                 window=window, frame="plane")


def sample_plane(network: DiskNetwork, point: ArrayLike, normal: ArrayLike, window_uv_m: ArrayLike) -> TraceMap:
    """Traces of a disk network on a plane, clipped to a window polygon in the plane's (u, v) frame.

    Parameters
    ----------
    network : DiskNetwork
    point : (3,) array_like of float
        A point o of the plane (x, y, z) in metres: the origin of (u, v).
    normal : (3,) array_like of float
        Plane normal m (normalised here); sets the frame of :func:`plane_frame`.
    window_uv_m : (k, 2) array_like of float or shapely.Polygon
        Window polygon in plane coordinates (u, v) in metres, valid, non-zero area; any orientation
        of its ring. Convex windows are clipped in numpy (Cyrus-Beck), others with shapely.

    Returns
    -------
    TraceMap
        One straight trace per disk cut (a non-convex window may split a trace into several), frame
        ``"plane"``, attributes ``set`` (set id) and ``disk`` (row in ``network``), window the given
        polygon. P21 = P32 / C23 and mean trace length π E[r²]/(2 E[r]) in expectation
        (docs/fractures.md §10.2, eqs. (7.2), (10.6); Wang 2005, Zhang et al. 2002;
        the mean length holds for untruncated traces).

    Examples
    --------
    >>> net = DiskNetwork([[0, 0, 0]], [[1, 0, 0]], [2.0], [0], [-5, -5, -5, 5, 5, 5])
    >>> tm = sample_plane(net, [0, 0, 0], [0, 0, 1], [(-5, -5), (5, -5), (5, 5), (-5, 5)])
    >>> tm.lengths_m().tolist()
    [4.0]
    """
    _require_network(network)
    origin = _point(point, "point")
    frame = plane_frame(normal)
    polygon = _window(window_uv_m)
    return _plane_traces(network.centre_m, network.normal, network.radius_m, network.set_id, origin,
                         frame, polygon)
