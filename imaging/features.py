r"""Per-pixel features for the learned joint detector: multi-scale ridge, edge, texture and
oriented line-support measures of a flattened face image (docs/imaging.md §3.1).

A thin dark line is what the ridge filter sees; a real joint is also a wide shadowed band, a step
edge between blocks lit differently, and above all *long*: minor cracks, rubble rims and plate
edges are short or curved. The features describe each pixel by

=====================  ===========================================================================
group                  features (σ in pixels)
=====================  ===========================================================================
brightness             the flattened grey level; its difference from Gaussian means at σ 3, 8, 20
dark ridges            Sato tubeness :math:`\sigma^2 \max(\lambda_1, 0)` at σ 1, 2, 4, 8, 12
bright ridges          the same of the negated image at σ 2, 4 (highlights, veins, plate rims)
edges                  gradient magnitude :math:`\sigma\,|\nabla G_\sigma * I|` at σ 1, 2, 4, 8
orientation            coherence of the structure tensor (Bigün & Granlund 1987), scales 4, 12
texture                local standard deviation at σ 4 and 16
line support           the dark-ridge and the edge maps averaged along line segments of 21 and 51 px
                       in 12 directions: the largest average, and how much it exceeds the mean
                       over directions (a long straight structure is large in one direction only)
=====================  ===========================================================================

All are scale-normalised (Lindeberg 1998) and use no per-image normalisation, so a model trained on
one set of images applies to another of similar pixel size. Filters of σ >= 4 px (the ridge and
edge responses, and the Gaussian means behind the contrast, the coherence and the local standard
deviation) and the line support run on a grid coarsened by 2 (:data:`COARSE_FROM_SIGMA`), which
the scale normalisation makes equivalent, at a quarter of the cost.
"""

from __future__ import annotations

import numpy as np

from .ridges import ridge_response

__all__ = ["FEATURE_NAMES", "CONTEXT_NAMES", "pixel_features", "context_features", "line_support"]

_RIDGE_SIGMAS = (1.0, 2.0, 4.0, 8.0, 12.0)
_BRIGHT_SIGMAS = (2.0, 4.0)
_EDGE_SIGMAS = (1.0, 2.0, 4.0, 8.0)
_CONTRAST_SIGMAS = (3.0, 8.0, 20.0)
_COHERENCE_SIGMAS = (4.0, 12.0)
_STD_SIGMAS = (4.0, 16.0)
_SUPPORT_LENGTHS = (21, 51)
_N_DIRECTIONS = 12

FEATURE_NAMES = (
    ("grey",)
    + tuple(f"contrast_{s:g}" for s in _CONTRAST_SIGMAS)
    + tuple(f"ridge_dark_{s:g}" for s in _RIDGE_SIGMAS)
    + tuple(f"ridge_bright_{s:g}" for s in _BRIGHT_SIGMAS)
    + tuple(f"edge_{s:g}" for s in _EDGE_SIGMAS)
    + tuple(f"coherence_{s:g}" for s in _COHERENCE_SIGMAS)
    + tuple(f"std_{s:g}" for s in _STD_SIGMAS)
    + tuple(f"{kind}_support_{n}_{stat}" for kind in ("ridge", "edge") for n in _SUPPORT_LENGTHS
            for stat in ("max", "excess"))
)

_CONTEXT_BLURS = (2.0, 6.0)
_CONTEXT_LENGTHS = (21, 51, 101)
CONTEXT_NAMES = (("probability",) + tuple(f"probability_blur_{s:g}" for s in _CONTEXT_BLURS)
                 + tuple(f"probability_support_{n}_{stat}" for n in _CONTEXT_LENGTHS
                         for stat in ("max", "excess")))


#: Filters at or above this scale (pixels) run on a grid coarsened by 2 and are resized back: the
#: scale-normalised responses are the same on either grid, at a quarter of the cost.
COARSE_FROM_SIGMA = 4.0


def _coarse(image):
    """The image on a grid coarsened by 2 (area averaging)."""
    import cv2

    h, w = image.shape
    return cv2.resize(image, (max(w // 2, 1), max(h // 2, 1)), interpolation=cv2.INTER_AREA)


def _fine(values, shape, out=None):
    """A coarse-grid map resized back to ``shape`` (bilinear), into ``out`` when given (a
    contiguous float32 map of that shape: no copy of the result)."""
    import cv2

    fine = cv2.resize(values, (shape[1], shape[0]), dst=out, interpolation=cv2.INTER_LINEAR)
    return _into(fine, out)


def _into(values, out):
    """``values``, written into ``out`` unless it is already there (or ``out`` is None)."""
    if out is None or values is out:
        return values
    out[...] = values
    return out


def _ridge(image, half, sigma, black=True, out=None):
    """Scale-normalised Sato response at one scale; on the coarse grid from COARSE_FROM_SIGMA."""
    if sigma < COARSE_FROM_SIGMA:
        return _into(ridge_response(image, [sigma], black_ridges=black, normalise=False), out)
    return _fine(ridge_response(half, [sigma / 2], black_ridges=black, normalise=False), image.shape,
                 out)


def _edge(image, half, sigma, out=None):
    """Scale-normalised gradient magnitude σ|∇G_σ * I|; on the coarse grid from COARSE_FROM_SIGMA."""
    if sigma < COARSE_FROM_SIGMA:
        g_r, g_c = _gradient(image, sigma)
        return _into(np.float32(sigma) * np.sqrt(g_r * g_r + g_c * g_c), out)
    g_r, g_c = _gradient(half, sigma / 2)
    return _fine(np.float32(sigma / 2) * np.sqrt(g_r * g_r + g_c * g_c), image.shape, out)


def _blur(image, sigma):
    import cv2

    return cv2.GaussianBlur(image, (0, 0), sigma, borderType=cv2.BORDER_REFLECT)


def _coherence(j_rr, j_cc, j_rc):
    """(λ1 - λ2) / (λ1 + λ2) of a smoothed structure tensor (0: no direction, 1: one)."""
    root = np.sqrt((j_rr - j_cc) ** 2 + 4 * j_rc * j_rc)
    return root / (j_rr + j_cc + np.float32(1e-6))


def _local_sd(mean, mean_of_square):
    """Standard deviation from the local means of a map and of its square."""
    return np.sqrt(np.maximum(mean_of_square - mean * mean, 0.0))


class _Pyramid:
    """Maps to be Gaussian-smoothed together and combined pixel by pixel, as the structure tensor's
    three products (coherence) or an image and its square (local standard deviation). From
    :data:`COARSE_FROM_SIGMA` the maps are smoothed at σ / 2 on the grid coarsened by 2 (made once,
    on first use unless given as ``coarse``), combined there and the result resized back: the
    combination of smooth maps is itself smooth, and a quarter of the pixels cost a quarter as much
    (an eighth for the blur, whose kernel is half as long)."""

    def __init__(self, *maps, coarse=None):
        self.maps, self._halves = maps, coarse

    def at(self, sigma, combine, out=None):
        if sigma < COARSE_FROM_SIGMA:
            return _into(combine(*(_blur(m, sigma) for m in self.maps)), out)
        if self._halves is None:
            self._halves = [_coarse(m) for m in self.maps]
        return _fine(combine(*(_blur(m, sigma / 2) for m in self._halves)), self.maps[0].shape, out)


def _gradient(image, sigma):
    """(d/drow, d/dcol) of the image smoothed at σ (Sobel on the smoothed image)."""
    import cv2

    smooth = _blur(image, sigma)
    g_r = cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3, scale=0.125, borderType=cv2.BORDER_REFLECT)
    g_c = cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3, scale=0.125, borderType=cv2.BORDER_REFLECT)
    return g_r, g_c


def line_support(values: np.ndarray, length_px: int, n_directions: int = _N_DIRECTIONS):
    r"""Averages of a map along line segments in ``n_directions`` directions.

    Parameters
    ----------
    values : (H, W) float32 ndarray
    length_px : int
        Segment length (odd), pixels.
    n_directions : int, default 12
        Directions evenly spaced over 0–180°.

    Returns
    -------
    (largest, excess) : two (H, W) float32 ndarrays
        :math:`\max_\theta \bar v_\theta` and :math:`\max_\theta \bar v_\theta - \operatorname{mean}_\theta
        \bar v_\theta`, with :math:`\bar v_\theta` the mean of the map over the segment of direction θ
        centred on the pixel (an anti-aliased line kernel).

    Examples
    --------
    >>> v = np.zeros((41, 41), np.float32); v[20, :] = 1.0
    >>> top, excess = line_support(v, 21)
    >>> round(float(top[20, 20]), 2), bool(excess[20, 20] > 0.5)
    (1.0, True)
    """
    import cv2

    n = int(length_px) | 1
    half = n // 2
    work = np.ascontiguousarray(values, dtype=np.float32)
    total = np.zeros(work.shape, np.float32)
    best = np.full(work.shape, -np.inf, np.float32)
    for k in range(n_directions):
        theta = np.pi * k / n_directions
        kernel = np.zeros((n, n), np.float32)
        dx, dy = half * np.cos(theta), half * np.sin(theta)
        p0 = (int(round((half - dx) * 16)), int(round((half - dy) * 16)))
        p1 = (int(round((half + dx) * 16)), int(round((half + dy) * 16)))
        cv2.line(kernel, p0, p1, 1.0, 1, cv2.LINE_AA, 4)
        kernel /= kernel.sum()
        mean = cv2.filter2D(work, cv2.CV_32F, kernel, borderType=cv2.BORDER_REFLECT)
        total += mean
        np.maximum(best, mean, out=best)
    return best, best - total / n_directions


def pixel_features(flat) -> np.ndarray:
    """The features of every pixel of a flattened face image (see the module notes).

    Parameters
    ----------
    flat : (H, W) array_like of float
        Grey image flattened by division (:func:`rockmass.imaging.enhance.flatten_illumination`,
        rock near 1); not modified.

    Returns
    -------
    (len(FEATURE_NAMES), H, W) float32 ndarray
        One map per feature, in the order of :data:`FEATURE_NAMES` (channels first: a pixel's
        features are a strided column, read by the classifier's matrix products without a copy).
    """
    image = np.array(flat, dtype=np.float32, copy=True)
    if image.ndim != 2:
        raise ValueError(f"flat must be a 2-D grey image, got shape {image.shape}")
    # each map is written into its row as it is made (the coarse-grid ones resized straight into
    # it): stacking a list of 27 maps at the end copied 27 x 4 MP x 4 bytes = 430 MB at 4 MP and
    # doubled the peak memory
    out = np.empty((len(FEATURE_NAMES),) + image.shape, np.float32)
    rows = iter(out)
    half = _coarse(image)
    _into(image, next(rows))
    levels = _Pyramid(image, coarse=[half])
    for s in _CONTRAST_SIGMAS:
        np.subtract(image, levels.at(s, lambda mean: mean), out=next(rows))
    dark = [_ridge(image, half, s, out=next(rows)) for s in _RIDGE_SIGMAS]
    for s in _BRIGHT_SIGMAS:
        _ridge(image, half, s, black=False, out=next(rows))
    edges = [_edge(image, half, s, out=next(rows)) for s in _EDGE_SIGMAS]
    g_r, g_c = _gradient(image, 1.0)
    tensor = _Pyramid(g_r * g_r, g_c * g_c, g_r * g_c)
    for s in _COHERENCE_SIGMAS:
        tensor.at(s, _coherence, out=next(rows))
    square = image * image
    moments = _Pyramid(image, square, coarse=[half, _coarse(square)])  # both σ on the coarse grid
    for s in _STD_SIGMAS:
        moments.at(s, _local_sd, out=next(rows))
    ridge = np.max(dark[1:4], axis=0)  # σ 2-8: the joints' widths
    edge = np.max(edges[1:3], axis=0)
    for source in (ridge, edge):  # on the coarse grid, segments of half the length
        coarse = _coarse(source)
        for n in _SUPPORT_LENGTHS:
            for v in line_support(coarse, n // 2):
                _fine(v, image.shape, out=next(rows))
    if next(rows, None) is not None:  # every row written, in FEATURE_NAMES order
        raise AssertionError("pixel_features wrote fewer maps than FEATURE_NAMES lists")
    return out


def context_features(probability) -> np.ndarray:
    """Context of a first-stage probability map, for the second stage (auto-context, Tu & Bai 2010).

    Parameters
    ----------
    probability : (H, W) array_like of float
        Joint probability from the first stage; not modified.

    Returns
    -------
    (len(CONTEXT_NAMES), H, W) float32 ndarray
        The probability, its Gaussian means at σ 2 and 6 px, and its :func:`line_support` (largest
        and excess) along 21, 51 and 101 px segments: whether a pixel lies on a long, straight run of
        likely joint pixels, or on a short or isolated one.
    """
    p = np.array(probability, dtype=np.float32, copy=True)
    if p.ndim != 2:
        raise ValueError(f"probability must be a 2-D map, got shape {p.shape}")
    out = [p] + [_blur(p, s) for s in _CONTEXT_BLURS]
    for n in _CONTEXT_LENGTHS:
        out += list(line_support(p, n))
    return np.stack(out).astype(np.float32, copy=False)
