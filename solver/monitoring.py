"""History points fixed on the excavation boundary: crown, invert, left and right wall.

UDEC users report the convergence of an opening from *history points* placed on its boundary: the
"history" command of UDEC (Itasca Consulting Group, UDEC User's Manual; version 3.0, 1996, is the
one Jiang et al. cite; docs/dem.md, References) records a displacement component at a chosen point
of the model every so many steps, and a point on the roof, the floor or a wall of the opening
belongs to the rock block that holds it, so it moves with that block. This module does the same
for rigid blocks:

1. :func:`boundary_points` finds the four classic points on the boundary of the opening left by
   the excavation stages removed so far (the union of their blocks) and attaches each one to the
   rock block on the other side of the boundary, as a material point of that block (its position
   about the block centroid in the reference placement, rotation 0).
2. :func:`point_positions` places those material points for any block positions and rotations;
   :func:`point_displacement` gives their displacement from the model as built, and
   :func:`point_displacement_from` their displacement from any reference placement (typically the
   state after initial equilibrium, as :func:`rockmass.solver.run` reports it).

Arrays: positions ``pos`` are block centroids, (..., n_blocks, 2) float64 in metres (x right,
y up), rotations ``rot`` (..., n_blocks) float64 in radians counter-clockwise, the leading axes
(frames, time) optional; :attr:`Engine.pos <rockmass.solver.engine.Engine>`, ``Engine.pos0`` and a
:class:`~rockmass.solver.Frame`'s ``position_m`` / ``rotation_rad`` have this layout.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["BoundaryPoint", "POINT_NAMES", "boundary_points", "point_positions",
           "point_displacement", "point_displacement_from"]

#: The points :func:`boundary_points` returns, in this order.
POINT_NAMES = ("crown", "invert", "left_wall", "right_wall")

#: The nudge off the boundary into the rock, as a fraction of the opening size (the diagonal of
#: its bounding box): far above round-off (the blockgen noding grid is ~1e-12 of the model size),
#: far below any block (blockgen's minimum edge is 2 % of a typical edge).
NUDGE_FRACTION = 1e-6

# outward direction of each point along the line it was found on
_OUTWARD = {"crown": (0.0, 1.0), "invert": (0.0, -1.0), "left_wall": (-1.0, 0.0),
            "right_wall": (1.0, 0.0)}


@dataclass(frozen=True, eq=False)
class BoundaryPoint:
    """A material point of one block, found on the excavation boundary.

    Attributes
    ----------
    name : str
        ``"crown"``, ``"invert"``, ``"left_wall"`` or ``"right_wall"``
        (see :func:`boundary_points`).
    block : int
        Index of the (rock-side, not excavated) block that carries the point.
    point_xy_m : (2,) float64
        The point in the model as built (m).
    local_xy_m : (2,) float64
        The point about the block's centroid in the block's reference frame (rotation 0):
        ``point_xy_m - model.centroid_xy_m[block]`` (m).
    """

    name: str
    block: int
    point_xy_m: np.ndarray
    local_xy_m: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "block", int(self.block))
        if self.block < 0:
            raise ValueError(f"BoundaryPoint {self.name!r}: block must be >= 0, got {self.block}")
        for field in ("point_xy_m", "local_xy_m"):
            a = np.array(getattr(self, field), dtype=np.float64)
            if a.shape != (2,):
                raise ValueError(f"BoundaryPoint {self.name!r}: {field} must have shape (2,), "
                                 f"got {a.shape}")
            a.setflags(write=False)
            object.__setattr__(self, field, a)

    def __repr__(self) -> str:
        x, y = self.point_xy_m
        return f"BoundaryPoint({self.name!r}, block {self.block}, at ({x:.6g}, {y:.6g}) m)"


# --------------------------------------------------------------------------------------- points --
def _stage_ids(model, regions) -> np.ndarray:
    """Region numbers (>= 1) from ids and/or stage names; ValueError naming what selects nothing."""
    names = list(model.region_names)
    items = [regions] if isinstance(regions, (str, int, np.integer)) else list(regions)
    if not items:
        raise ValueError("regions is empty: give the excavation stages removed so far (region ids "
                         f">= 1 or names; this model has {_stage_list(model)})")
    ids, unknown = [], []
    for item in items:
        if isinstance(item, str):
            if item in names[1:]:
                ids.append(names.index(item))
            else:
                unknown.append(item)
        elif isinstance(item, (int, np.integer)) and not isinstance(item, bool):
            ids.append(int(item))
        else:
            raise TypeError(f"regions must hold region ids (int) or stage names (str), got "
                            f"{item!r} ({type(item).__name__})")
    ids = np.unique(np.asarray(ids, np.int64))
    present = np.unique(model.region[model.region > 0])
    missing = [int(k) for k in ids if k < 1 or k not in present] + unknown
    if missing:
        raise ValueError(f"regions {missing} select no excavated block (region ids are >= 1, 0 is "
                         f"the rock that stays; this model has {_stage_list(model)})")
    return ids


def _stage_list(model) -> str:
    present = np.unique(model.region[model.region > 0])
    if not len(present):
        return "no excavation stages"
    return ", ".join(f"{int(k)} = {model.region_names[k]!r}" for k in present)


def _ring_segments(geom) -> np.ndarray:
    """(n, 2, 2) edges of every ring (shells and holes) of a Polygon / MultiPolygon."""
    import shapely

    rings = shapely.get_rings(shapely.get_parts(geom))
    xy, ring = shapely.get_coordinates(rings, return_index=True)
    same = ring[1:] == ring[:-1]  # rings are closed: consecutive coordinates of one ring
    return np.stack([xy[:-1][same], xy[1:][same]], axis=1)


def _crossings(seg: np.ndarray, axis: int, value: float) -> np.ndarray:
    """The other coordinate of every point where the line ``xy[axis] == value`` meets the edges
    ``seg`` ((n, 2, 2)); an edge lying on the line gives both its ends."""
    other = 1 - axis
    a = seg[:, 0, axis] - value
    b = seg[:, 1, axis] - value
    on = (a == 0) & (b == 0)
    cross = (a * b <= 0) & ~on
    t = a[cross] / (a[cross] - b[cross])  # a != b: not both zero
    p0, p1 = seg[cross, 0, other], seg[cross, 1, other]
    return np.concatenate([p0 + t * (p1 - p0), seg[on, 0, other], seg[on, 1, other]])


def _extremes(opening):
    """(4, 2) crown, invert, left and right wall of a (Multi)Polygon and its size (bounding-box
    diagonal); None for the points when a line misses (separate parts on either side of it).

    The vertical line through the centroid and the horizontal line at mid-height always meet a
    connected polygon: its projection on either axis is an interval holding that coordinate."""
    import shapely

    x0, y0, x1, y1 = opening.bounds
    size = float(np.hypot(x1 - x0, y1 - y0))
    xc = float(shapely.centroid(opening).x)
    ymid = 0.5 * (y0 + y1)
    seg = _ring_segments(opening)
    ys = _crossings(seg, 0, xc)
    xs = _crossings(seg, 1, ymid)
    if not len(ys) or not len(xs):
        return None, size
    return np.array([[xc, ys.max()], [xc, ys.min()], [xs.min(), ymid], [xs.max(), ymid]]), size


def boundary_points(model, regions) -> list[BoundaryPoint]:
    """Crown, invert and wall points of an opening, each attached to the rock block that holds it.

    The opening is the union of the blocks of the excavation stages ``regions``. Its four points
    are the usual UDEC history-point locations for tunnel convergence (see the module docstring):

    ``crown``
        the highest point of the opening's boundary on the vertical line through the opening's
        centroid (the roof above the middle of the opening);
    ``invert``
        the lowest point of the boundary on that line (the floor);
    ``left_wall``, ``right_wall``
        the left-most and right-most boundary points on the horizontal line at the opening's
        mid-height, half-way between its lowest and highest point.

    Each point is given to the block on the rock side of the boundary: among the blocks that
    stay (every block whose region is not in ``regions``; blocks of later stages count, they are
    still in place), the one nearest to the point nudged outwards by 1e-6 of the opening size
    along the line the point was found on (away from the opening: up for the crown, down for the
    invert, left and right for the walls); the block that contains the nudged point if there is
    one, else the nearest (ties: the block whose centroid is nearest).

    Parameters
    ----------
    model : BlockModel
        The block model (:class:`rockmass.blockgen.BlockModel`), as built (rotation 0).
    regions : int, str or sequence of int / str
        The excavation stages removed so far: region ids (``model.region`` values >= 1) or stage
        names (``model.region_names[1:]``), in any order; duplicates are ignored.

    Returns
    -------
    list of BoundaryPoint
        In the order of :data:`POINT_NAMES`.

    Raises
    ------
    ValueError
        When a region selects no block (id 0, an id or name not in the model), naming the regions
        and listing the model's stages; when no block stays.
    TypeError
        When ``regions`` holds something other than ints and strings.

    Warns
    -----
    UserWarning
        When the opening is in separate parts and a line falls between them (the points are then
        those of the largest part); when the block found for a point does not touch it (the
        opening reaches the domain outline there, so no rock lies beyond it).

    Notes
    -----
    Stages are removed in order, so after stage k ``regions`` is usually ``range(1, k + 1)``. The
    invert of a stage above a later one (the arch above its benches) lies on a block of that later
    stage: its history ends when that stage is excavated. An opening of several separate parts is
    treated as one (its points are the extremes over all parts) while both lines meet it; when one
    misses (twin tunnels side by side, or an arch and a lower bench without the bench between),
    the points are those of the largest part. For a connected opening both lines always meet it.

    Examples
    --------
    >>> from rockmass.blockgen import JointSet, build, rectangle
    >>> m = build([(0, 0), (4, 0), (4, 3), (0, 3)],
    ...           [JointSet(0, 1.0, origin_xy_m=(0, 0)), JointSet(90, 1.0, origin_xy_m=(0.5, 0))],
    ...           excavations=[rectangle((2.0, 1.5), 2.0, 1.0, name="drift")])
    >>> for p in boundary_points(m, ["drift"]):
    ...     print(p.name, p.point_xy_m.tolist(), int(m.region[p.block]), p.local_xy_m.tolist())
    crown [2.0, 2.0] 0 [0.0, -0.5]
    invert [2.0, 1.0] 0 [0.0, 0.5]
    left_wall [1.0, 1.5] 0 [0.25, 0.0]
    right_wall [3.0, 1.5] 0 [-0.25, 0.0]
    """
    import shapely

    ids = _stage_ids(model, regions)
    removed = np.isin(model.region, ids)
    stays = np.flatnonzero(~removed)
    if not len(stays):
        raise ValueError(f"regions {ids.tolist()} remove every block: no rock is left to hold the "
                         "boundary points")
    polys = model.to_shapely()
    opening = shapely.union_all(polys[removed])
    where = f"the opening of regions {ids.tolist()}"
    xy, size = _extremes(opening)
    if xy is None:  # separate parts, a line between them: the largest part (a connected one)
        parts = shapely.get_parts(opening)
        largest = parts[np.argmax(shapely.area(parts))]
        warnings.warn(f"{where} has {len(parts)} separate parts and the line through its centroid "
                      "or at its mid-height misses them: the points are those of its largest part "
                      f"({shapely.area(largest):.6g} m², bounds {np.round(largest.bounds, 6)})",
                      stacklevel=2)
        xy, size = _extremes(largest)
    nudged = xy + NUDGE_FRACTION * size * np.array([_OUTWARD[n] for n in POINT_NAMES])

    # blocks that stay, against the nudged points: (n_stays, 4)
    cand = polys[stays]
    pts = shapely.points(nudged)
    dist = shapely.distance(cand[:, None], pts[None, :])
    inside = shapely.contains(cand[:, None], pts[None, :])
    gap_xy = model.centroid_xy_m[stays][:, None, :] - nudged[None, :, :]
    cdist = np.hypot(gap_xy[..., 0], gap_xy[..., 1])
    out = []
    for k, name in enumerate(POINT_NAMES):
        order = np.lexsort((cdist[:, k], dist[:, k], ~inside[:, k]))  # contains, nearest, centroid
        block = int(stays[order[0]])
        gap = float(shapely.distance(polys[block], shapely.points(xy[k])))
        if gap > NUDGE_FRACTION * size:
            warnings.warn(f"{name} of {where} at ({xy[k, 0]:.6g}, {xy[k, 1]:.6g}) m is "
                          f"{gap:.3g} m from the nearest block that stays ({block}): no rock "
                          "beyond the opening there (the domain outline?)", stacklevel=2)
        out.append(BoundaryPoint(name, block, xy[k], xy[k] - model.centroid_xy_m[block]))
    return out


# -------------------------------------------------------------------------------- displacement --
def _point_arrays(points) -> tuple[list, np.ndarray, np.ndarray]:
    points = list(points)
    for p in points:
        if not isinstance(p, BoundaryPoint):
            raise TypeError(f"points must be BoundaryPoint objects, got {type(p).__name__}")
    names = [p.name for p in points]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"points: names must be unique (they key the result), repeated: {dup}")
    block = np.array([p.block for p in points], np.int64)
    local = np.array([p.local_xy_m for p in points], np.float64).reshape(-1, 2)
    return names, block, local


def _placement(pos, rot, n_block_min: int, pos_name: str, rot_name: str):
    pos = np.asarray(pos, dtype=np.float64)
    rot = np.asarray(rot, dtype=np.float64)
    if pos.ndim < 2 or pos.shape[-1] != 2:
        raise ValueError(f"{pos_name} must have shape (..., n_blocks, 2), got {pos.shape}")
    if rot.shape != pos.shape[:-1]:
        raise ValueError(f"{rot_name} must have shape {pos.shape[:-1]} (one angle per block of "
                         f"{pos_name}), got {rot.shape}")
    if pos.shape[-2] < n_block_min:
        raise ValueError(f"{pos_name} has {pos.shape[-2]} blocks but a point is on block "
                         f"{n_block_min - 1}")
    return pos, rot


def point_positions(points, pos, rot) -> np.ndarray:
    """Where the material points are for block centroids ``pos`` and rotations ``rot``.

    x = pos[b] + R(rot[b]) · local, R(θ) the counter-clockwise rotation by θ.

    Parameters
    ----------
    points : sequence of BoundaryPoint
        From :func:`boundary_points` (or built by hand).
    pos : (..., n_blocks, 2) array_like of float
        Block centroids (m); leading axes (frames) broadcast.
    rot : (..., n_blocks) array_like of float
        Block rotations (rad, counter-clockwise) from the reference frame of ``local_xy_m``.

    Returns
    -------
    (..., n_points, 2) float64
        Point coordinates (m).

    Examples
    --------
    >>> p = BoundaryPoint("crown", 0, (1.0, 2.0), (0.0, 1.0))
    >>> point_positions([p], [[1.0, 1.0]], [np.pi / 2]).round(12).tolist()
    [[0.0, 1.0]]
    """
    _, block, local = _point_arrays(points)
    pos, rot = _placement(pos, rot, int(block.max(initial=-1)) + 1, "pos", "rot")
    c, s = np.cos(rot[..., block]), np.sin(rot[..., block])
    return np.stack([pos[..., block, 0] + c * local[:, 0] - s * local[:, 1],
                     pos[..., block, 1] + s * local[:, 0] + c * local[:, 1]], axis=-1)


def _as_dict(names, u) -> dict:
    mag = np.hypot(u[..., 0], u[..., 1])
    scalar = u.ndim == 2
    out = {}
    for k, name in enumerate(names):
        for key, v in ((f"{name}_ux_m", u[..., k, 0]), (f"{name}_uy_m", u[..., k, 1]),
                       (f"{name}_u_m", mag[..., k])):
            out[key] = float(v) if scalar else np.array(v)
    return out


def _displacement(points, pos, rot, ref_pos, ref_rot):
    names, block, local = _point_arrays(points)
    need = int(block.max(initial=-1)) + 1
    pos, rot = _placement(pos, rot, need, "pos", "rot")
    ref_pos, ref_rot = _placement(ref_pos, ref_rot, need, "ref_pos", "ref_rot")
    # u = (p - p0) + (R(θ) - R(θ0)) l with the differences of cos and sin in half-angle form
    # (cos θ - cos θ0 = -2 sin(σ) sin(δ), sin θ - sin θ0 = 2 cos(σ) sin(δ), σ = (θ+θ0)/2,
    # δ = (θ-θ0)/2): no cancellation for the small rotations of a static run
    th, th0 = rot[..., block], ref_rot[..., block]
    half_sum, sin_half = 0.5 * (th + th0), np.sin(0.5 * (th - th0))
    dc = -2.0 * np.sin(half_sum) * sin_half
    ds = 2.0 * np.cos(half_sum) * sin_half
    dp = pos[..., block, :] - ref_pos[..., block, :]
    u = np.stack([dp[..., 0] + dc * local[:, 0] - ds * local[:, 1],
                  dp[..., 1] + ds * local[:, 0] + dc * local[:, 1]], axis=-1)
    return names, u


def point_displacement(points, pos, rot, pos0) -> dict:
    """Displacement of each point from the model as built.

    u = (pos[b] + R(rot[b]) l) − (pos0[b] + l), l the point's ``local_xy_m`` and ``pos0`` the
    block centroids as built (``model.centroid_xy_m``, ``Engine.pos0``), where every rotation is 0.

    Parameters
    ----------
    points : sequence of BoundaryPoint
        Unique names.
    pos : (..., n_blocks, 2) array_like of float
        Present block centroids (m); leading axes (frames, time) broadcast.
    rot : (..., n_blocks) array_like of float
        Present block rotations (rad, counter-clockwise).
    pos0 : (n_blocks, 2) array_like of float
        Reference centroids at rotation 0 (m).

    Returns
    -------
    dict
        ``"<name>_ux_m"``, ``"<name>_uy_m"`` (components, m) and ``"<name>_u_m"`` (length, m) for
        every point, the same keys as the runner's history columns; floats for one placement,
        arrays of the leading shape of ``pos`` otherwise.

    Examples
    --------
    >>> p = BoundaryPoint("crown", 0, (1.0, 2.0), (0.0, 1.0))
    >>> u = point_displacement([p], [[1.0, 1.0]], [np.pi / 2], [[1.0, 1.0]])
    >>> {k: round(v, 12) for k, v in u.items()}
    {'crown_ux_m': -1.0, 'crown_uy_m': -1.0, 'crown_u_m': 1.414213562373}
    """
    pos0 = np.asarray(pos0, dtype=np.float64)
    names, u = _displacement(points, pos, rot, pos0, np.zeros(pos0.shape[:-1]))
    return _as_dict(names, u)


def point_displacement_from(points, pos, rot, ref_pos, ref_rot) -> dict:
    """Displacement of each point from a reference placement (e.g. after initial equilibrium).

    u = (pos[b] + R(rot[b]) l) − (ref_pos[b] + R(ref_rot[b]) l): the motion of the same material
    point between the two placements, so the settlement under gravity and in-situ stress before
    excavation drops out (the runner's ``ref``, taken after a first static stage without
    excavation). With ``ref_pos = pos0`` and ``ref_rot = 0`` it is :func:`point_displacement`.

    Parameters
    ----------
    points : sequence of BoundaryPoint
    pos, ref_pos : (..., n_blocks, 2) array_like of float
        Present and reference block centroids (m); leading axes broadcast.
    rot, ref_rot : (..., n_blocks) array_like of float
        Present and reference rotations (rad) from the frame of ``local_xy_m``.

    Returns
    -------
    dict
        As :func:`point_displacement`.

    Examples
    --------
    >>> p = BoundaryPoint("invert", 0, (0.0, -1.0), (0.0, -1.0))
    >>> u = point_displacement_from([p], [[0.0, 0.5]], [0.0], [[0.0, 0.0]], [np.pi])
    >>> {k: round(v, 12) + 0.0 for k, v in u.items()}
    {'invert_ux_m': 0.0, 'invert_uy_m': -1.5, 'invert_u_m': 1.5}
    """
    names, u = _displacement(points, pos, rot, ref_pos, ref_rot)
    return _as_dict(names, u)
