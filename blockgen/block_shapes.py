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

__all__ = ["BlockShapes", "block_shapes", "VolumeDistribution", "volume_distribution", "PieceQuality",
           "piece_quality", "VOLUME_QUANTILES"]


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


@dataclass(frozen=True)
class VolumeDistribution:
    """The in-situ block volumes as a distribution: ``quantiles`` (probability → m³), the lognormal
    fitted by maximum likelihood (``log_mean``, ``log_sd``: mean and standard deviation of ln V)
    and its Kolmogorov–Smirnov distance ``ks_distance`` to the sample (a measure of fit; with
    fitted parameters its usual p-value would be too generous, so none is given)."""

    count: int
    total_m3: float
    mean_m3: float
    quantiles: dict
    log_mean: float
    log_sd: float
    ks_distance: float


#: probabilities of the reported volume quantiles.
VOLUME_QUANTILES = (0.1, 0.25, 0.5, 0.75, 0.9)


def volume_distribution(volume_m3: np.ndarray) -> VolumeDistribution:
    """Quantiles and the lognormal fit of block volumes (all > 0).

    >>> d = volume_distribution(np.exp(np.random.default_rng(0).normal(1.0, 0.5, 4000)))
    >>> round(d.log_mean, 1), round(d.log_sd, 1), d.ks_distance < 0.03
    (1.0, 0.5, True)
    """
    from scipy.stats import kstest

    v = np.sort(np.asarray(volume_m3, float))
    if len(v) == 0:
        return VolumeDistribution(0, 0.0, 0.0, {}, math.nan, math.nan, math.nan)
    logs = np.log(v)
    mu, sd = float(logs.mean()), float(logs.std())
    ks = float(kstest(logs, "norm", args=(mu, sd)).statistic) if sd > 0 and len(v) > 1 else math.nan
    return VolumeDistribution(len(v), float(v.sum()), float(v.mean()),
                              {str(q): float(np.quantile(v, q)) for q in VOLUME_QUANTILES}, mu, sd, ks)


@dataclass(frozen=True)
class PieceQuality:
    """Convex pieces a mechanical model would struggle with: ``tiny`` (volume below
    ``tiny_fraction`` of the box), ``slivers`` (smallest equivalent-ellipsoid semi-axis below
    ``sliver_ratio`` of the largest), the ``smallest_m3`` piece and the thresholds used."""

    tiny: int
    slivers: int
    smallest_m3: float
    tiny_fraction: float
    sliver_ratio: float


def piece_quality(blocks, tiny_fraction: float = 1e-9, sliver_ratio: float = 0.01) -> PieceQuality:
    """Count the tiny and sliver pieces of a :class:`~rockmass.blockgen.blocks3d.BlockSet3D` (rock
    pieces only), from their volumes and second moments."""
    rock = ~blocks.excavated
    volume = blocks.volume_m3[rock]
    if not len(volume):
        return PieceQuality(0, 0, 0.0, tiny_fraction, sliver_ratio)
    box_volume = float(np.prod(blocks.box_m[1] - blocks.box_m[0]))
    centroid = blocks.centroid_m[rock]
    covariance = (blocks.second_moment_m5[rock] / volume[:, None, None]
                  - np.einsum("bi,bj->bij", centroid, centroid))
    eigen = np.clip(np.linalg.eigvalsh(covariance), 0.0, None)      # ascending
    thin = np.sqrt(eigen[:, 0]) < sliver_ratio * np.sqrt(eigen[:, 2])
    return PieceQuality(int((volume < tiny_fraction * box_volume).sum()), int(thin.sum()),
                        float(volume.min()), tiny_fraction, sliver_ratio)
