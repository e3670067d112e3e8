"""Coarser grids for the learned detector: the same face at fewer pixels per joint width
(docs/imaging.md §3.4).

The pixel model's features have fixed pixel scales and its probability bands keep about the same
width whatever the joints' (§3.1), so it finds joints best at the pixel size it was trained at.
A photograph taken with more pixels per joint width shows its joints wide and soft: the
detector breaks them into short pieces and keeps texture between them. Since a photograph's
pixel size says little about its joints' width in pixels, the learned detector runs on the
working grid and on that grid coarsened by each factor of ``ExtractParams.learned_levels``, and
the grid whose traces are the most joint-like is kept: the one of highest length-weighted mean
joint score (eq. (7.1)),

.. math:: \\bar s = \\frac{\\sum_i L_i s_i}{\\sum_i L_i},

the finer grid on a tie, among the grids whose traces add up to at least
:data:`MIN_LENGTH_SHARE` of the working grid's trace length (a coarser grid that keeps only a few
joint-like traces, as on a face in flat light, is not a better view of the face); and a coarser
grid whose joint-like length :math:`L \\bar s` is :data:`JOINT_LENGTH_RATIO` times the finer
grid's is kept even at a lower mean score (the finer grid found only a few clean pieces). A
coarser grid costs a quarter (factor 2) or a sixteenth (factor 4) of the working grid's pixels.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["MIN_LEVEL_SIDE_PX", "MIN_LENGTH_SHARE", "JOINT_LENGTH_RATIO",
           "usable_levels", "coarsen", "resized", "to_grid", "mean_joint_score",
           "choose_level", "kept_grid"]

#: A coarser grid is tried only when its shorter side keeps at least this many pixels.
MIN_LEVEL_SIDE_PX = 64
#: A coarser grid is kept only when its traces' total length is at least this share of the
#: working grid's: the largest share that changes no choice on the real ``train/`` photographs
#: (as they are and enlarged 2 and 4 times) and refuses a grid with a handful of traces.
MIN_LENGTH_SHARE = 0.3
#: ... or when its joint-like length (trace length times mean joint score) is at least this many
#: times the finer grid's: a working grid that finds only a few clean pieces of wide joints. 2 and
#: 3 scored about the same on ``train/``; 3 kept the trace length error lower.
JOINT_LENGTH_RATIO = 3.0


def usable_levels(levels: Sequence[int], shape_px: tuple[int, int]) -> tuple[int, ...]:
    """The factors of ``levels`` whose coarsened grid keeps :data:`MIN_LEVEL_SIDE_PX` a side.

    Examples
    --------
    >>> usable_levels((2, 4), (300, 400)), usable_levels((2, 4), (200, 400))
    ((2, 4), (2,))
    """
    return tuple(int(f) for f in levels if min(shape_px) // int(f) >= MIN_LEVEL_SIDE_PX)


def coarsen(grey: np.ndarray, mask: np.ndarray | None, level: int):
    """(image, mask, shape) on the grid coarsened ``level`` times per side (area averaging; a
    coarse pixel is in the mask when most of it was)."""
    import cv2

    h, w = grey.shape
    shape = (max(h // level, 1), max(w // level, 1))
    image = cv2.resize(grey, shape[::-1], interpolation=cv2.INTER_AREA)
    if mask is None:
        return image, None, shape
    share = cv2.resize(mask.astype(np.float32), shape[::-1], interpolation=cv2.INTER_AREA)
    return image, share >= 0.5, shape


def resized(image: np.ndarray, shape_px: tuple[int, int]) -> np.ndarray:
    """A map of a coarser grid shown on a finer one (nearest pixel: binary maps stay binary);
    ``image`` itself when it has that shape already."""
    import cv2

    image = np.asarray(image)
    if image.shape[:2] == tuple(shape_px):
        return image
    kind = np.uint8 if image.dtype == bool else image.dtype
    out = cv2.resize(image.astype(kind), (shape_px[1], shape_px[0]), interpolation=cv2.INTER_NEAREST)
    return out.astype(bool) if image.dtype == bool else out


def to_grid(chains: Sequence[np.ndarray], from_shape, to_shape) -> list[np.ndarray]:
    """Pixel polylines (row, col) moved from one grid to another over the same image (pixel
    centres: x_to + 0.5 = (x_from + 0.5) · n_to / n_from per axis).

    Examples
    --------
    >>> to_grid([np.array([[0.0, 1.0]])], (50, 50), (100, 100))[0].tolist()
    [[0.5, 2.5]]
    """
    ratio = np.array([to_shape[0] / from_shape[0], to_shape[1] / from_shape[1]])
    return [(np.asarray(c, dtype=np.float64) + 0.5) * ratio - 0.5 for c in chains]


def mean_joint_score(traces) -> float:
    """Length-weighted mean ``joint_score`` of a trace map (0 with no traces)."""
    if traces.n_traces == 0:
        return 0.0
    lengths = traces.lengths_m()
    total = float(lengths.sum())
    if not total > 0:
        return 0.0
    return float(np.dot(lengths, np.asarray(traces.attributes["joint_score"], dtype=float)) / total)


def choose_level(scores: Mapping[int, float], lengths: Mapping[int, float], *,
                 min_length_share: float = MIN_LENGTH_SHARE,
                 joint_length_ratio: float = JOINT_LENGTH_RATIO) -> int:
    """The grid whose traces are the most joint-like (see the module notes).

    From the working grid (level 1), each coarser level in turn replaces the choice so far when
    its mean joint score is higher and its trace length is at least ``min_length_share`` of level
    1's, or when its joint-like length L·s̄ is at least ``joint_length_ratio`` times the choice's.

    Parameters
    ----------
    scores, lengths : mappings level -> float
        Length-weighted mean joint score and total trace length of each level's traces (level 1
        among them).

    Examples
    --------
    >>> choose_level({1: 0.6, 2: 0.7, 4: 0.65}, {1: 10.0, 2: 8.0, 4: 6.0})
    2
    >>> choose_level({1: 0.6, 2: 0.6}, {1: 10.0, 2: 10.0})  # a tie: the finer grid
    1
    >>> choose_level({1: 0.6, 2: 0.7}, {1: 10.0, 2: 1.0})  # a handful of traces: not a better view
    1
    >>> choose_level({1: 0.7, 2: 0.6}, {1: 5.0, 2: 50.0})  # ten times the joints found
    2
    """
    best = 1
    for level in sorted(f for f in scores if f != 1):
        better = scores[level] > scores[best] and lengths[level] >= min_length_share * lengths[1]
        more = scores[level] * lengths[level] >= joint_length_ratio * scores[best] * lengths[best]
        if better or (more and lengths[level] > 0):
            best = level
    return best


def kept_grid(by_level: Mapping[int, object]) -> tuple[int, dict | None]:
    """The level :func:`choose_level` keeps among a learned chain's trace maps by level (level 1,
    the working grid, among them), and the record of the choice (``levels``, ``joint_score``,
    ``traces``, ``length`` per level, ``kept``; None when level 1 was the only one run)."""
    if set(by_level) == {1}:
        return 1, None
    levels = sorted(by_level)
    scores = {f: mean_joint_score(by_level[f]) for f in levels}
    lengths = {f: float(by_level[f].lengths_m().sum()) for f in levels}
    level = choose_level(scores, lengths)
    return level, {"levels": levels, "joint_score": [scores[f] for f in levels],
                   "traces": [by_level[f].n_traces for f in levels],
                   "length": [lengths[f] for f in levels], "kept": level}
