"""Binary trace images as box-counting input: reading, thresholding, thinning and padding.

Rules
-----
- Any non-zero pixel is a trace pixel. An image with more than two grey levels, or with two levels
  neither of which is 0, is not binary: it needs a ``threshold`` (pixels strictly above it are
  traces); ``invert=True`` first turns dark lines on a light background into light lines.
- Lines must be 1 pixel wide (docs/fractal.md §2.1: 3-px lines raise D from 1.37 to 1.54). With
  ``skeletonize="auto"`` an image is thinned (scikit-image's ``skeletonize``, Zhang & Suen 1984) when
  (a) more than ``THICK_FRACTION`` of its trace pixels lie in a fully occupied 2 x 2 block (a 1-pixel
  line, 4- or 8-connected, has none except where two lines cross), (b) its mean line width,
  2 x trace pixels / boundary pixels, is at most ``MAX_LINE_WIDTH_PX`` — wider means filled areas,
  not lines (a filled square), which thinning would destroy — and (c) thinning removes enough to
  matter: trace pixels / skeleton pixels above ``MIN_THICK_WIDTH`` (a Sierpinski carpet, already
  thin, would lose 4 of 262,144 pixels and is left as it is).
  The result says what was done and why.
- Box sizes must tile the grid exactly, so a non-square image, or a square one whose side has fewer
  than 3 divisors up to a quarter of it, is padded with empty pixels (bottom and right) to the
  smallest side that is a product of 2, 3 and 5 with at least 12 divisors.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["PreparedImage", "read_image", "prepare_binary_image", "divisors", "THICK_FRACTION"]

THICK_FRACTION = 0.95
# Measured on random networks at 360² (the networks of benchmarks/bench_fractal_boxcount.py): 1-pixel
# lines put 4 % (2 % fill) to 90 % (67 % fill, saturated) of their pixels in full 2x2 blocks; lines
# drawn 2-6 px wide 97.8-99 % at every density. Reference fractals on their base grids: 0-90 %.
MIN_THICK_WIDTH = 1.05  # pixels / skeleton pixels below which thinning changes too little
MAX_LINE_WIDTH_PX = 15.0  # mean width (px) above which the image holds filled areas, not lines
SKELETONIZE_CHOICES = ("auto", "always", "never")


@dataclass(frozen=True)
class PreparedImage:
    """A square uint8 trace mask ready for counting, and what was done to make it."""

    mask: np.ndarray
    original_shape: tuple[int, int]
    skeletonized: bool
    notes: tuple[str, ...]


def divisors(n: int) -> np.ndarray:
    """All divisors of ``n`` in ascending order, ``int64``.

    Examples
    --------
    >>> divisors(360).size, divisors(12).tolist()
    (24, [1, 2, 3, 4, 6, 12])
    """
    small = [d for d in range(1, int(np.sqrt(n)) + 1) if n % d == 0]
    return np.array(sorted(set(small + [n // d for d in small])), dtype=np.int64)


def _is_5_smooth(n: int) -> bool:
    for p in (2, 3, 5):
        while n % p == 0:
            n //= p
    return n == 1


def padded_side(height: int, width: int) -> int:
    """Side of the square grid an image of this shape is counted on (see the module rules)."""
    side = max(height, width)
    if height == width and np.count_nonzero(divisors(side) <= side / 4) >= 3:
        return side
    m = side
    while not (_is_5_smooth(m) and divisors(m).size >= 12):
        m += 1
    return m


def read_image(path) -> np.ndarray:
    """Read a PNG / TIFF / JPEG / BMP as a 2-D grey array (8 or 16 bit kept as read).

    Colour images are converted to grey (ITU-R 601 luma, as OpenCV does). An alpha channel is
    dropped, except when the colour is uniform and only the alpha varies (lines drawn by opacity on
    a transparent canvas): then the alpha channel is the image. Raises ``OSError`` naming the file
    when it is missing or not an image.
    """
    import cv2

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    data = np.fromfile(path, dtype=np.uint8)
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if img is None:
        raise OSError(f"{path}: not a readable image (PNG, TIFF, JPEG or BMP expected)")
    if img.ndim == 3:
        if img.shape[2] == 4:
            colour, alpha = img[:, :, :3], img[:, :, 3]
            if colour.min() == colour.max() and alpha.min() != alpha.max():
                return np.ascontiguousarray(alpha)
            return cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY)
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    return img


def _pack_rows(mask: np.ndarray, width: int) -> np.ndarray:
    """Bit rows ``(h, ceil(width / 64)) uint64`` of a (h, w) mask: bit c of a row is bit c % 64 of
    word c // 64, set when pixel (row, c mod w) is not 0, for c < width (w <= width <= 2 w); the
    bits from ``width`` on are 0. The repeated columns let a box that wraps round the right edge of
    a cyclic grid be one run of bits."""
    h, w = mask.shape
    if width > w:
        mask = np.concatenate([mask, mask[:, :width - w]], axis=1)
    packed = np.packbits(mask, axis=1, bitorder="little")
    words = np.zeros((h, (width + 63) // 64 * 8), dtype=np.uint8)
    words[:, :packed.shape[1]] = packed
    return words.view("<u8").astype(np.uint64, copy=False)  # little-endian words, native order


def _set_bits(words: np.ndarray) -> int:
    """Set bits of a uint64 array (``np.bitwise_count`` from numpy 2.0; unpacked bytes before)."""
    if hasattr(np, "bitwise_count"):
        return int(np.bitwise_count(words).sum())
    return int(np.count_nonzero(np.unpackbits(np.ascontiguousarray(words).view(np.uint8))))


def _line_counts(mask: np.ndarray) -> tuple[int, int, int]:
    """(trace pixels, pixels in a full 2 x 2 block, interior pixels) of a (h, w) mask.

    A pixel is interior when its four edge neighbours are all traces (pixels outside the image
    count as background). Whole bit rows are combined 64 pixels at a time: with ``left`` / ``right``
    moving a row one column right / left, a full block with top-left pixel (r, c) is bit c of
    ``P & right(P)``, P = row r & row r + 1, and a pixel lies in a full block when a block starts
    at it or one column, one row, or both before it.
    """
    bits = _pack_rows(mask, mask.shape[1])  # the bits past the last column are 0
    one, top = np.uint64(1), np.uint64(63)

    def left(x):  # bit c: bit c - 1 of the row
        out = x << one
        out[:, 1:] |= x[:, :-1] >> top
        return out

    def right(x):  # bit c: bit c + 1 of the row
        out = x >> one
        out[:, :-1] |= x[:, 1:] << top
        return out

    mid = bits[1:-1]
    interior = _set_bits(mid & bits[:-2] & bits[2:] & left(mid) & right(mid))
    pair = bits[:-1] & bits[1:]
    start = pair & right(pair)  # full blocks with top-left (r, c)
    start |= left(start)  # ... or (r, c - 1)
    in_block = np.zeros_like(bits)
    in_block[:-1] |= start
    in_block[1:] |= start
    return _set_bits(bits), _set_bits(in_block), interior


def _line_statistics(mask: np.ndarray) -> tuple[float, float]:
    """(fraction of trace pixels in a fully occupied 2 x 2 block, mean line width in pixels).

    The mean width is 2 * area / boundary pixels (a band of width w and length L has w L pixels and
    about 2 L boundary pixels); it is large for filled areas and about 2 for 1-pixel lines.
    """
    n, in_block, interior = _line_counts(mask)
    if n == 0:
        return 0.0, 0.0
    return in_block / n, 2.0 * n / max(n - interior, 1)


def prepare_binary_image(image, *, threshold: float | None = None, invert: bool = False,
                         skeletonize: str = "auto", name: str = "image") -> PreparedImage:
    """Turn a grey or binary image into a square 1-pixel trace mask for box counting.

    Parameters
    ----------
    image : (H, W) array_like
        Grey levels (any numeric dtype) or booleans. Not modified.
    threshold : float, optional
        Pixels strictly above it are traces (after ``invert``). Required for non-binary images.
    invert : bool, default False
        Use ``max - value`` first (dark lines on a light background).
    skeletonize : {"auto", "always", "never"}, default "auto"
        Thin the lines to 1 pixel: when they are thick (``auto``), always, or never.
    name : str
        Name used in error messages (the file name, for the CLI).

    Returns
    -------
    PreparedImage

    Raises
    ------
    ValueError
        Not 2-D, non-finite values, not binary without a threshold, or no trace pixel.
    """
    if skeletonize not in SKELETONIZE_CHOICES:
        raise ValueError(f"skeletonize must be one of {', '.join(SKELETONIZE_CHOICES)}, "
                         f"got {skeletonize!r}")
    img = np.asarray(image)
    if img.ndim != 2 or min(img.shape) < 1:
        raise ValueError(f"{name}: a binary image must be 2-D, got shape {img.shape}")
    if img.dtype == bool:
        img = img.astype(np.uint8)
    if not np.issubdtype(img.dtype, np.number):
        raise TypeError(f"{name}: image must be numeric or boolean, got dtype {img.dtype}")
    if np.issubdtype(img.dtype, np.floating) and not np.isfinite(img).all():
        raise ValueError(f"{name}: image contains NaN or infinite values")
    notes = []
    if invert:
        top = np.iinfo(img.dtype).max if np.issubdtype(img.dtype, np.integer) else img.max()
        img = top - img.astype(np.float64 if img.dtype.kind == "f" else np.int64)
        notes.append(f"grey levels inverted (v -> {top} - v: dark lines on a light background)")
    if threshold is not None:
        if isinstance(threshold, (bool, np.bool_)) or not isinstance(threshold, (int, float, np.number)):
            raise TypeError(f"threshold must be a number (a grey level), got {threshold!r}")
        if not np.isfinite(threshold):
            raise ValueError(f"{name}: threshold must be finite, got {threshold}")
        mask = img > threshold
        n_trace = int(np.count_nonzero(mask))
        notes.append(f"thresholded: pixels > {threshold:g} are traces")
    else:
        mask = img != 0
        n_trace = int(np.count_nonzero(mask))
        level = img.flat[np.argmax(mask)]  # binary: every non-zero pixel has this level
        if n_trace and np.count_nonzero(img == level) != n_trace:
            levels = np.unique(img)
            raise ValueError(
                f"{name}: image is not binary ({levels.size} grey levels, from {levels[0]} to "
                f"{levels[-1]}); give a threshold (pixels above it are traces), and invert if the "
                f"lines are dark on a light background")
    if n_trace == 0:
        raise ValueError(f"{name}: image is empty (no trace pixel)")
    if n_trace > 0.5 * mask.size:
        notes.append(f"warning: {100 * n_trace / mask.size:.0f}% of pixels are traces; "
                     "if the lines are dark on a light background, invert the image")
    skeletonized = False
    frac, width = _line_statistics(mask)
    if skeletonize == "always" or (skeletonize == "auto" and frac > THICK_FRACTION
                                   and width <= MAX_LINE_WIDTH_PX):
        from skimage.morphology import skeletonize as _skeletonize

        thin = _skeletonize(mask)
        n_thin = max(int(thin.sum()), 1)
        if skeletonize == "always" or n_trace / n_thin > MIN_THICK_WIDTH:
            mask = thin
            skeletonized = True
            notes.append(f"lines thinned to 1 pixel (skeletonised): {n_trace} -> {n_thin} trace "
                         f"pixels, mean line width {width:.1f} px")
    elif skeletonize == "auto" and frac > THICK_FRACTION:
        notes.append(f"image holds filled areas (mean width {width:.0f} px > "
                     f"{MAX_LINE_WIDTH_PX:g} px), not lines: counted as drawn, not thinned")
    elif frac > THICK_FRACTION:
        notes.append(f"warning: lines look thicker than 1 pixel ({100 * frac:.0f}% of pixels in "
                     "filled 2x2 blocks) and were not thinned; D will be biased high")
    h, w = mask.shape
    side = padded_side(h, w)
    if side != h or side != w:
        padded = np.zeros((side, side), dtype=np.uint8)
        padded[:h, :w] = mask
        notes.append(f"padded with empty pixels from {h}x{w} to {side}x{side} so box sizes tile "
                     "the grid exactly")
        out = padded
    else:  # a bool mask is viewed as 0/1 bytes, not converted
        out = mask.view(np.uint8) if mask.dtype == bool else mask
        out = np.ascontiguousarray(out, dtype=np.uint8)
    return PreparedImage(out, (h, w), skeletonized, tuple(notes))
