"""Small block models built by hand, whose answers can be worked out on paper.

Each builder returns a :class:`~rockmass.blockgen.BlockModel` and documents its block indices.
Blocks that touch the domain outline get a domain contact ``(block, -1)`` so that side selectors,
:class:`~rockmass.solver.BoundaryStress` and quiet boundaries find their edges.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from rockmass.blockgen.model import KIND_DOMAIN, KIND_JOINT, BlockModel

__all__ = ["rect", "rotate", "hand_model", "incline", "column", "shear_box", "jointed_rectangle"]


def rect(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Counter-clockwise rectangle [x0, x1] × [y0, y1]."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)


def rotate(xy, angle_deg: float) -> np.ndarray:
    """Points rotated counter-clockwise about the origin."""
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return np.asarray(xy, float) @ np.array([[c, -s], [s, c]]).T


def hand_model(polygons, pairs=(), set_of_pair=None, set_names=("j",), domain_xy_m=None,
               region=None) -> BlockModel:
    """A BlockModel from CCW polygons.

    ``pairs``: (i, j) block pairs in contact; the contact length is the length of their shared
    boundary (shapely). ``set_of_pair``: joint-set index of each pair (default 0). ``domain_xy_m``:
    the outline (default: the bounding box of all blocks); every block with boundary on it gets a
    domain contact of that length.
    """
    polygons = [np.asarray(p, float) for p in polygons]
    shapes = [shapely.Polygon(p) for p in polygons]
    for k, s in enumerate(shapes):
        if not s.is_valid or s.exterior.is_ccw is False:
            raise ValueError(f"polygon {k} must be valid and counter-clockwise")
    if domain_xy_m is None:
        x0, y0, x1, y1 = shapely.union_all(shapes).bounds
        domain_xy_m = rect(x0, y0, x1, y1)
    ring = shapely.LinearRing(domain_xy_m)
    blocks, lengths, kinds, sources = [], [], [], []
    set_of_pair = [0] * len(pairs) if set_of_pair is None else list(set_of_pair)
    for (i, j), src in zip(pairs, set_of_pair):
        blocks.append((i, j))
        lengths.append(shapes[i].boundary.intersection(shapes[j].boundary).length)
        kinds.append(KIND_JOINT)
        sources.append(src)
    for k, s in enumerate(shapes):
        on = s.boundary.intersection(ring.buffer(1e-9)).length
        if on > 1e-9:
            blocks.append((k, -1))
            lengths.append(on)
            kinds.append(KIND_DOMAIN)
            sources.append(-1)
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polygons])])
    region = np.zeros(len(polygons), int) if region is None else region
    n_regions = int(max(region)) + 1 if len(region) else 1
    return BlockModel(np.vstack(polygons), offsets, region,
                      ("rock",) + tuple(f"stage {k}" for k in range(1, n_regions)),
                      np.array(blocks, int).reshape(-1, 2), lengths, kinds, sources, tuple(set_names),
                      np.asarray(domain_xy_m, float))


def incline(psi_deg: float, b: float = 1.0, h: float = 0.5, base_length: float = 10.0,
            vertical_sides: bool = False) -> BlockModel:
    """Block 1 (b × h, base centred on the origin) on block 0 (base_length × 1 m), the pair turned
    counter-clockwise by ψ: the slope rises to the right, down-slope is −(cos ψ, sin ψ). With ψ = 0
    it is a block on a horizontal table. No domain contacts (the outline is far away).

    ``vertical_sides``: block 1 is instead the parallelogram on the same base with vertical sides of
    height h, so its centroid lies straight above the middle of its base: the weight needs no
    moment from the base and the normal stress under it is uniform (the closed forms of docs/dem.md
    §13 problem 1 assume the mean stresses).
    """
    half = base_length / 2
    base = rotate(rect(-half, -1.0, half, 0.0), psi_deg)
    top = rotate(rect(-b / 2, 0.0, b / 2, h), psi_deg)
    if vertical_sides:
        p0, p1 = top[0], top[1]
        top = np.array([p0, p1, p1 + (0.0, h), p0 + (0.0, h)])
    far = 2 * max(half, h, b) + 1
    return hand_model([base, top], [(0, 1)], domain_xy_m=rect(-far, -far, far, far))


def column(n: int, s: float = 1.0, width: float = 1.0) -> BlockModel:
    """Block 0: a base [0, width] × [−s, 0]; blocks 1..n of height s stacked on it (block n on top).
    The domain is the bounding box, so the top face of block n is the ``"top"`` side."""
    polys = [rect(0.0, (k - 1) * s, width, k * s) for k in range(n + 1)]
    return hand_model(polys, [(k, k + 1) for k in range(n)])


def shear_box(b: float = 1.0, h: float = 0.5, cap_stiff: bool = False) -> BlockModel:
    """Direct shear: block 0 a long lower half [−b, 2b] × [−h, 0] (the sheared sample stays on it),
    block 1 the upper half [0, b] × [0, h] (joint set 0, ``"shear"``). With ``cap_stiff`` a
    block 2 [−b/2, 3b/2] × [h, 2h] above it (joint set 1, ``"cap"``) is the constant-normal-stiffness
    spring. The domain outline is the bounding box of the pieces."""
    polys = [rect(-b, -h, 2 * b, 0.0), rect(0.0, 0.0, b, h)]
    pairs, sets = [(0, 1)], [0]
    if cap_stiff:
        polys.append(rect(-b / 2, h, 1.5 * b, 2 * h))
        pairs.append((1, 2))
        sets.append(1)
    return hand_model(polys, pairs, sets, set_names=("shear", "cap"))


def jointed_rectangle(width: float = 4.0, height: float = 3.0, spacing: float = 1.0,
                      angles=(30.0, 115.0)):
    """A rectangle [0, width] × [0, height] cut by two persistent joint sets (blockgen.build)."""
    from rockmass.blockgen import JointSet, build

    return build(rect(0.0, 0.0, width, height),
                 [JointSet(angles[0], spacing, origin_xy_m=(0.3, 0.2), name="a"),
                  JointSet(angles[1], spacing, origin_xy_m=(0.1, 0.4), name="b")])
