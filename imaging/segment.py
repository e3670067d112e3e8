"""Ridge response to a binary joint mask: robust hysteresis threshold, region of interest, cleanup.

docs/imaging.md §4, eq. (4.1): a global Otsu threshold over-segments rock texture. The ridge response of a face
is mostly texture with a long tail of joints, so the thresholds are set from robust statistics of
the response (median and MAD, which the tail barely moves) and applied by hysteresis: a pixel above
the low threshold is kept only when it is connected to a pixel above the high one, which keeps a
joint's faint stretches and drops isolated texture.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .frame import check_scale, uv_to_rc

__all__ = ["robust_thresholds", "roi_mask", "segment_ridges", "hysteresis_mask", "remove_small_objects",
           "fill_holes"]

#: MAD of a normal distribution times this is its standard deviation.
MAD_TO_SIGMA = 1.482602218505602
#: Share of the positive responses that seed lines when no response reaches the high threshold.
SEED_FRACTION = 0.005


def robust_thresholds(response, *, low_k: float, high_k: float, mask=None) -> tuple[float, float]:
    r"""Hysteresis thresholds from the median and MAD of the ridge response.

    Parameters
    ----------
    response : (H, W) array_like of float
        Ridge response (:func:`rockmass.imaging.ridges.ridge_response`).
    low_k, high_k : float
        Thresholds in robust standard deviations above the median, 0 <= low_k <= high_k.
    mask : (H, W) bool array_like, optional
        Only these pixels enter the statistics (the region of interest).

    Returns
    -------
    (low, high) : tuple of float
        :math:`t = m + k \cdot 1.4826\,\mathrm{MAD}` with m the median of the *positive* responses
        and MAD their median absolute deviation.

    Notes
    -----
    Sato's response is clipped at 0, and on a face about half the pixels (the convex side of the
    texture) are exactly 0; the statistics are taken over the positive pixels, which are the
    texture's ridge-like half and the joints. When the high threshold would exceed every
    response — lines that are no rare tail: wide mortar joints, dense fracturing — it is lowered to
    the (1 - SEED_FRACTION) quantile (and the low one scaled with it), so the strongest 0.5 % of
    pixels still seed lines instead of nothing being found.

    Examples
    --------
    >>> r = np.array([0.0, 1.0, 2.0, 3.0, 100.0])
    >>> robust_thresholds(r, low_k=1.0, high_k=2.0)
    (3.982602218505602, 5.465204437011204)
    """
    if not (0 <= low_k <= high_k):
        raise ValueError(f"low_k and high_k must satisfy 0 <= low_k <= high_k, got {low_k!r}, {high_k!r}")
    values = np.asarray(response)
    if mask is not None:
        values = values[np.asarray(mask, dtype=bool)]
    values = values[values > 0].astype(np.float64, copy=False)
    if values.size == 0:
        raise ValueError("the ridge response is zero everywhere (in the region of interest): "
                         "the image has no dark lines to find")
    if values.size > 2_000_000:  # a regular subsample gives the same quantiles to < 0.1 %
        values = values[:: values.size // 1_000_000]
    median = float(np.median(values))
    scale = MAD_TO_SIGMA * float(np.median(np.abs(values - median)))
    low, high = median + low_k * scale, median + high_k * scale
    # where lines fill much of the image (wide mortar, dense joints) the tail is not a tail and
    # high can exceed every response: let at least the top SEED_FRACTION of pixels seed lines
    if high >= float(values.max()):
        ceiling = float(np.quantile(values, 1.0 - SEED_FRACTION))
        low, high = low * ceiling / high, ceiling
    return low, high


def roi_mask(roi, shape_px, *, m_per_px: float | None = None) -> np.ndarray:
    """Boolean mask of a region-of-interest polygon (sky, shotcrete, equipment left outside).

    Parameters
    ----------
    roi : (k, 2) array_like, or mapping with one key ``"rc_px"`` or ``"uv_m"``
        Polygon vertices (k >= 3): a bare array or ``{"rc_px": ...}`` is in pixel (row, col);
        ``{"uv_m": ...}`` is in metres on the face frame (needs ``m_per_px``).
    shape_px : (rows, cols)
        Image shape.
    m_per_px : float, optional
        Scale, for a polygon in metres.

    Returns
    -------
    (rows, cols) bool ndarray
        True inside the polygon (pixel centres inside or on its boundary).

    Raises
    ------
    ValueError
        Fewer than 3 vertices, non-finite vertices, zero area, a polygon that does not overlap the
        image, a mapping with another key, or metres without a scale (each message names ``roi``).
    """
    import cv2

    rc = roi_vertices_rc(roi, shape_px, m_per_px=m_per_px)
    h, w = (int(v) for v in shape_px)
    mask = np.zeros((h, w), dtype=np.uint8)
    xy = np.round(rc[:, ::-1] * 16).astype(np.int32)  # cv2: (x=col, y=row), 4-bit subpixel
    cv2.fillPoly(mask, [xy], 1, lineType=cv2.LINE_8, shift=4)
    if not mask.any():
        raise ValueError(f"roi: the polygon covers no pixel centre of the {h} x {w} image")
    return mask.astype(bool)


def roi_vertices_rc(roi, shape_px, *, m_per_px: float | None = None) -> np.ndarray:
    """The ROI polygon as (k, 2) float64 pixel (row, col) vertices, validated (see :func:`roi_mask`)."""
    import shapely

    if isinstance(roi, Mapping):
        keys = set(roi)
        if keys == {"rc_px"}:
            units, vertices = "px", roi["rc_px"]
        elif keys == {"uv_m"}:
            units, vertices = "m", roi["uv_m"]
        else:
            raise ValueError(f"roi must have exactly one key, 'rc_px' (pixels) or 'uv_m' (metres), "
                             f"got {sorted(map(str, keys))}")
    else:
        units, vertices = "px", roi
    array = np.asarray(vertices, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2 or array.shape[0] < 3:
        raise ValueError(f"roi must be a polygon of at least 3 (k, 2) vertices, got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError("roi has non-finite vertices")
    h, w = (int(v) for v in shape_px)
    if units == "m":
        if m_per_px is None:
            raise ValueError("roi is in metres ('uv_m') but no scale is known: set m_per_px or "
                             "control_points, or give the roi in pixels ('rc_px')")
        array = uv_to_rc(array, h, check_scale(m_per_px))
    polygon = shapely.Polygon(array)
    if polygon.area == 0:
        raise ValueError("roi encloses zero area")
    image = shapely.box(-0.5, -0.5, h - 0.5, w - 0.5)
    if not polygon.intersects(image) or polygon.intersection(image).area == 0:
        raise ValueError(f"roi lies outside the {h} x {w} image (rows 0..{h - 1}, cols 0..{w - 1}; "
                         f"roi rows {array[:, 0].min():.1f}..{array[:, 0].max():.1f}, "
                         f"cols {array[:, 1].min():.1f}..{array[:, 1].max():.1f})")
    return array


def remove_small_objects(binary: np.ndarray, min_size_px: int) -> np.ndarray:
    """Drop 8-connected components of fewer than ``min_size_px`` pixels (a new array)."""
    import cv2

    binary = np.asarray(binary, dtype=bool)
    if min_size_px <= 1 or not binary.any():
        return binary.copy()
    n, labels, stats, _ = cv2.connectedComponentsWithStats(binary.view(np.uint8), connectivity=8)
    keep = stats[:, cv2.CC_STAT_AREA] >= min_size_px
    keep[0] = False  # background
    return keep[labels]


def fill_holes(binary, max_area_px: int) -> np.ndarray:
    """Fill the holes of a binary mask: 4-connected background pieces of fewer than ``max_area_px``
    pixels that do not touch the image border (a new array).

    A wide dark band is often cut by a brighter rib or speck, and its mask then has holes; thinned,
    each hole becomes a loop of two parallel lines around it (docs/imaging.md §4).

    Examples
    --------
    >>> b = np.zeros((7, 7), bool); b[1:6, 1:6] = True; b[3, 3] = False
    >>> int(fill_holes(b, 2).sum()), int(fill_holes(b, 1).sum())
    (25, 24)
    """
    import cv2

    binary = np.asarray(binary, dtype=bool)
    if max_area_px <= 1 or binary.all() or not binary.any():
        return binary.copy()
    background = np.pad(~binary, 1, constant_values=True)  # the border joins one outer piece
    n, labels, stats, _ = cv2.connectedComponentsWithStats(background.view(np.uint8), connectivity=4)
    small = stats[:, cv2.CC_STAT_AREA] < max_area_px
    small[0] = False  # label 0: the mask's own pixels
    small[labels[0, 0]] = False  # the outer piece, holding the padded frame
    return binary | small[labels[1:-1, 1:-1]]


def segment_ridges(response, *, low_k: float = 2.0, high_k: float = 6.0, min_size_px: int = 30,
                   mask=None) -> np.ndarray:
    """Binary joint mask: hysteresis threshold of the ridge response, ROI, small objects removed.

    Parameters
    ----------
    response : (H, W) array_like of float
        Ridge response.
    low_k, high_k : float, default 2.0, 6.0
        Hysteresis thresholds in robust standard deviations (see :func:`robust_thresholds`).
    min_size_px : int, default 30
        Smallest 8-connected component kept, pixels.
    mask : (H, W) bool array_like, optional
        Region of interest; pixels outside it are never joints.

    Returns
    -------
    (H, W) bool ndarray

    References
    ----------
    .. [1] Canny, J. (1986). A computational approach to edge detection. IEEE Transactions on
       Pattern Analysis and Machine Intelligence 8(6), 679-698 (hysteresis thresholding).
    """
    values = np.asarray(response, dtype=np.float32)
    low, high = robust_thresholds(values, low_k=low_k, high_k=high_k, mask=mask)
    return hysteresis_mask(values, low=low, high=high, min_size_px=min_size_px, mask=mask)


def hysteresis_mask(response, *, low: float, high: float, min_size_px: int = 30, mask=None) -> np.ndarray:
    """Hysteresis threshold (Canny 1986): the 8-connected pieces of {R >= low, R > 0} that hold a
    pixel with R >= high, limited to ``mask``, pieces under ``min_size_px`` pixels removed.

    Parameters
    ----------
    response : (H, W) array_like of float
        Ridge response or joint probability; not modified.
    low, high : float
        Thresholds, low <= high.
    min_size_px : int, default 30
    mask : (H, W) bool array_like, optional
        Region of interest.

    Returns
    -------
    (H, W) bool ndarray

    Examples
    --------
    >>> r = np.zeros((5, 12)); r[2, 1:11] = 0.6; r[2, 5] = 0.9; r[0, 0:3] = 0.6
    >>> hysteresis_mask(r, low=0.5, high=0.8, min_size_px=1).sum(axis=1).tolist()
    [0, 0, 10, 0, 0]
    """
    import cv2

    if not low <= high:
        raise ValueError(f"low ({low!r}) must not exceed high ({high!r})")
    values = np.asarray(response, dtype=np.float32)
    candidate = (values >= low) & (values > 0)
    if mask is not None:
        candidate &= np.asarray(mask, dtype=bool)
    # hysteresis: keep the 8-connected pieces of {R >= low} that hold a pixel with R >= high
    # (inclusive, so a line of constant response on a flat image, where MAD = 0, is kept)
    n, labels = cv2.connectedComponents(candidate.view(np.uint8), connectivity=8, ltype=cv2.CV_32S)
    seeded = np.zeros(n, dtype=bool)
    seeded[np.unique(labels[candidate & (values >= high)])] = True
    seeded[0] = False
    return remove_small_objects(seeded[labels], int(min_size_px))
