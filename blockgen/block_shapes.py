"""Size and shape of 3D in-situ blocks: volume, surface area, sphericity and principal axes.

An in-situ block may be made of several convex pieces glued across fictitious faces
(:mod:`rockmass.blockgen.blocks3d`); its moments are the sums of theirs. Shape (docs/blocks.md §10):

- **Equivalent ellipsoid.** The uniform ellipsoid with the block's volume-normalised second moments
  about its centroid has semi-axes a ≥ b ≥ c with a² = 5 λ₁ … (λ the eigenvalues of the covariance
  C = ∫(x − x̄)(x − x̄)ᵀ dV / V), since a uniform ellipsoid has variance a²/5 along its axis a.
  ``elongation`` = b/a and ``flatness`` = c/b (1 for a cube or a sphere; a 1 × 2 × 3 box gives 2/3
  and 1/2). These describe what Kalenchuk et al. (2006) characterise with their α (shortening of
  the minor axis) and β (elongation of the major axis), but are not their factors.
- **Sphericity** Ψ = π^(1/3) (6V)^(2/3) / A (Wadell 1935): 1 for a sphere, 0.806 for a cube, smaller
  for slabs and rods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["BlockShapes", "block_shapes"]


@dataclass(frozen=True)
class BlockShapes:
    """Per in-situ block: ``volume_m3``, ``surface_area_m2`` (its outer surface: fictitious faces
    inside a block are not counted), ``centroid_m (n, 3)``, ``semi_axes_m (n, 3)`` (a ≥ b ≥ c),
    ``elongation`` b/a, ``flatness`` c/b and ``sphericity``."""

    volume_m3: np.ndarray
    surface_area_m2: np.ndarray
    centroid_m: np.ndarray
    semi_axes_m: np.ndarray
    elongation: np.ndarray
    flatness: np.ndarray
    sphericity: np.ndarray


def block_shapes(blocks) -> BlockShapes:
    """Size and shape of every in-situ block of a :class:`~rockmass.blockgen.blocks3d.BlockSet3D`.

    >>> from rockmass.blockgen.blocks3d import cut_box
    >>> shapes = block_shapes(cut_box([[0, 0, 0], [1, 2, 3]]))
    >>> np.round(shapes.elongation, 6).tolist(), np.round(shapes.flatness, 6).tolist()
    ([0.666667], [0.5])
    """
    n = blocks.n_blocks
    rock = blocks.block_id >= 0
    ids = blocks.block_id[rock]
    volume = np.bincount(ids, weights=blocks.volume_m3[rock], minlength=n)
    first = np.zeros((n, 3))
    second = np.zeros((n, 3, 3))
    np.add.at(first, ids, blocks.volume_m3[rock, None] * blocks.centroid_m[rock])
    np.add.at(second, ids, blocks.second_moment_m5[rock])
    area = np.bincount(ids, weights=blocks.surface_area_m2[rock], minlength=n)
    inner = ~blocks.excavated[blocks.links[:, 0]] & (blocks.block_id[blocks.links[:, 0]]
                                                    == blocks.block_id[blocks.links[:, 1]])
    np.subtract.at(area, blocks.block_id[blocks.links[inner, 0]], 2.0 * blocks.link_area_m2[inner])
    centroid = first / volume[:, None]
    covariance = second / volume[:, None, None] - np.einsum("bi,bj->bij", centroid, centroid)
    eigen = np.clip(np.linalg.eigvalsh(covariance)[:, ::-1], 0.0, None)
    axes = np.sqrt(5.0 * eigen)
    return BlockShapes(volume, area, centroid, axes, axes[:, 1] / axes[:, 0], axes[:, 2] / axes[:, 1],
                       math.pi ** (1 / 3) * (6 * volume) ** (2 / 3) / area)
