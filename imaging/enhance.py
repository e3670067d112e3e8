"""Photographs in, flat grey images out: reading, grey conversion and illumination flattening.

The first step of the extraction chain (docs/imaging.md §2). A face photograph is read with Pillow
(EXIF orientation honoured), converted to one float32 grey channel, and its illumination — a
gradient across the face, vignetting, soft shadows — divided out, so that a joint is as dark
relative to its surroundings in a shadow as in the light.

Arrays are (row, col) images; nothing here knows about metres.
"""

from __future__ import annotations

import contextlib
import warnings
from pathlib import Path

import numpy as np

__all__ = ["read_photo", "to_grey", "estimate_background", "flatten_illumination",
           "FLATTEN_METHODS"]

#: ITU-R BT.601 luma weights (R, G, B), the weights OpenCV and Pillow use for grey conversion.
LUMA_601 = (0.299, 0.587, 0.114)
FLATTEN_METHODS = ("divide", "subtract", "none")


#: Largest piece of a file handed to Pillow's decoder at once, bytes (:func:`read_photo`): a
#: 100 MP JPEG is about 50 MB; a larger file (trailing data, an uncompressed TIFF) is decoded in
#: pieces of this size.
_DECODE_BLOCK_MAX = 1 << 28


def read_photo(path, max_pixels: int | None = None) -> np.ndarray:
    """Read a JPEG / PNG / TIFF photograph as stored, after applying its EXIF orientation.

    Parameters
    ----------
    path : str or path-like
        The image file.
    max_pixels : int, optional
        The pixel count the caller has already allowed for this file (the commands check the
        header against ``--max-pixels`` first, :mod:`rockmass.image_limits`); Pillow's own
        decompression-bomb guard is then set to it instead of its default (about 179 MP refused).
        Default None: Pillow's default guard.

    Returns
    -------
    (H, W) or (H, W, 3) or (H, W, 4) ndarray
        uint8 for 8-bit files, uint16 for 16-bit grey files (Pillow modes ``I;16``, ``I``), float32
        for floating-point TIFFs; colour as RGB(A). Rotated / mirrored as the EXIF ``Orientation``
        tag says, so rows run top to bottom as the photographer saw the face.

    Raises
    ------
    FileNotFoundError
        When ``path`` is not a file.
    OSError
        When the file is empty, truncated or not an image (the message names the file).

    Notes
    -----
    Pillow's :func:`PIL.ImageOps.exif_transpose` applies the orientation; OpenCV's ``imdecode``
    would too, but does not read 16-bit colour consistently across builds. A truncated file is an
    error here, not a partly grey picture (Pillow's ``LOAD_TRUNCATED_IMAGES`` stays off).
    """
    from PIL import Image, ImageOps, UnidentifiedImageError

    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{path}: a folder, not a photograph")
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        with _pillow_pixel_limit(Image, max_pixels), Image.open(path) as img:
            # the file to the decoder in one call (up to _DECODE_BLOCK_MAX bytes): Pillow hands it
            # 64 kB at a time, and takes the GIL back between the pieces, which lets another
            # thread (``rockmass extract`` imports matplotlib meanwhile) double the decoding time
            # of a 12 MP JPEG. ``decodermaxblock`` is Pillow's block size for its decoders
            block = getattr(img, "decodermaxblock", 1 << 16)
            img.decodermaxblock = max(block, min(path.stat().st_size, _DECODE_BLOCK_MAX))
            img.load()
            img = ImageOps.exif_transpose(img)
            mode = img.mode
            if mode in ("I;16", "I;16B", "I;16L", "I;16N"):
                array = np.asarray(img, dtype=np.uint16)
            elif mode == "I":
                array = np.asarray(img).astype(np.int64)
                array = np.clip(array, 0, 65535).astype(np.uint16)
            elif mode == "F":
                array = np.asarray(img, dtype=np.float32)
            elif mode in ("L", "RGB", "RGBA"):
                array = np.asarray(img)
            elif mode == "1":
                array = np.asarray(img.convert("L"))
            elif mode in ("LA", "PA"):
                array = np.asarray(img.convert("L"))
            else:  # P, CMYK, YCbCr, ...
                array = np.asarray(img.convert("RGB"))
    except UnidentifiedImageError as exc:
        raise OSError(f"{path}: not a readable image (JPEG, PNG or TIFF expected)") from exc
    except (OSError, SyntaxError, ValueError) as exc:
        raise OSError(f"{path}: the image could not be decoded (truncated or corrupt?): {exc}") from exc
    return np.array(array, copy=True)



@contextlib.contextmanager
def _pillow_pixel_limit(image_module, max_pixels: int | None):
    """Pillow's ``Image.MAX_IMAGE_PIXELS`` raised to ``max_pixels`` for the block (Pillow refuses
    above twice that value and warns above it; the caller's own check is the guard then), and put
    back afterwards. ``None``: unchanged."""
    if max_pixels is None:
        yield
        return
    before = image_module.MAX_IMAGE_PIXELS
    image_module.MAX_IMAGE_PIXELS = max(int(max_pixels), before or 0)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", image_module.DecompressionBombWarning)
            yield
    finally:
        image_module.MAX_IMAGE_PIXELS = before

def to_grey(image, *, name: str = "image") -> np.ndarray:
    """One float32 grey channel in [0, 1] from a grey, RGB or RGBA image of any numeric dtype.

    Parameters
    ----------
    image : (H, W), (H, W, 3) or (H, W, 4) array_like
        bool, unsigned or signed integers (scaled by the dtype's maximum: 8 bit by 255, 16 bit by
        65535), or floats (taken as they are, assumed in [0, 1]; they must be finite). Colour
        channels are in RGB order; an alpha channel is ignored.
    name : str, default "image"
        Name used in error messages.

    Returns
    -------
    (H, W) ndarray of float32
        Luma :math:`Y = 0.299 R + 0.587 G + 0.114 B` (ITU-R BT.601) for colour input. A new
        array: the input is never modified.

    Raises
    ------
    TypeError
        Non-numeric dtype.
    ValueError
        Wrong shape, or non-finite float values (the message names ``name``).

    Examples
    --------
    >>> to_grey(np.array([[0, 255]], dtype=np.uint8)).tolist()
    [[0.0, 1.0]]
    >>> float(to_grey(np.full((1, 1, 3), 65535, dtype=np.uint16))[0, 0])
    1.0
    """
    array = np.asarray(image)
    if array.dtype.kind not in "biuf":
        raise TypeError(f"{name} must hold numbers (grey levels), got dtype {array.dtype}")
    if array.ndim == 3 and array.shape[2] in (3, 4):
        channels = array[..., :3]
    elif array.ndim == 2:
        channels = None
    else:
        raise ValueError(f"{name} must have shape (H, W), (H, W, 3) or (H, W, 4), got {array.shape}")
    if array.dtype.kind == "b":
        scale = 1.0
    elif array.dtype.kind in "iu":
        scale = 1.0 / float(np.iinfo(array.dtype).max)
    else:
        scale = 1.0
        if not np.isfinite(array).all():
            raise ValueError(f"{name} has non-finite (NaN or inf) pixel values")
    if channels is None:
        grey = array.astype(np.float32) * np.float32(scale)
    else:
        # channel by channel: a 24 MP photo never has a float copy of all three channels
        grey = np.zeros(array.shape[:2], dtype=np.float32)
        for k, weight in enumerate(LUMA_601):
            grey += channels[..., k].astype(np.float32) * np.float32(weight * scale)
    return np.ascontiguousarray(grey, dtype=np.float32)


def estimate_background(grey: np.ndarray, *, line_width_px: float, sigma_px: float) -> np.ndarray:
    r"""Large-scale illumination of a face, with dark joints removed first.

    Parameters
    ----------
    grey : (H, W) float32 ndarray
        Grey image (from :func:`to_grey`).
    line_width_px : float
        Widest dark line to remove, pixels (> 0). A grey closing with a disk of diameter
        :math:`2\lceil w \rceil + 1` fills every dark line up to this width.
    sigma_px : float
        Standard deviation of the Gaussian smoothing of the closed image, pixels (> 0); larger than
        the rock grains, smaller than the shadows.

    Returns
    -------
    (H, W) float32 ndarray
        :math:`B = G_\sigma * (I \bullet D_w)`, the closing of the image by the disk smoothed.

    Notes
    -----
    The closing (dilation then erosion) removes dark lines before smoothing, so the background is
    not pulled down along dense joint sets, which a plain blur would do.
    """
    import cv2

    radius = int(np.ceil(line_width_px))
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    closed = cv2.morphologyEx(grey, cv2.MORPH_CLOSE, disk, borderType=cv2.BORDER_REFLECT)
    return _gaussian_blur(closed, sigma_px)


def _gaussian_blur(image: np.ndarray, sigma_px: float) -> np.ndarray:
    """Gaussian blur, computed on a grid coarsened by sigma / 4 for wide kernels (sigma > 8 px).

    A smooth field sampled at a quarter of its sigma and resized up (bilinear) differs from the
    full-resolution blur by far less than a grey level; the cost falls with the square of the step.
    """
    import cv2

    h, w = image.shape
    step = sigma_px / 4.0 if sigma_px > 8.0 else 1.0
    if step <= 1.0:
        return cv2.GaussianBlur(image, (0, 0), sigma_px, borderType=cv2.BORDER_REFLECT)
    small = cv2.resize(image, (max(int(round(w / step)), 2), max(int(round(h / step)), 2)),
                       interpolation=cv2.INTER_AREA)
    small = cv2.GaussianBlur(small, (0, 0), 4.0, borderType=cv2.BORDER_REFLECT)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)


def flatten_illumination(grey, *, line_width_px: float = 3.0, sigma_px: float = 40.0,
                         method: str = "divide", clahe: bool = False,
                         clahe_clip_limit: float = 0.01, clahe_tile_px: int = 128) -> np.ndarray:
    r"""Remove uneven lighting from a grey face image.

    Parameters
    ----------
    grey : (H, W) array_like of float
        Grey image in [0, 1] (from :func:`to_grey`); not modified.
    line_width_px : float, default 3.0
        Widest joint to keep out of the background estimate, pixels (see
        :func:`estimate_background`).
    sigma_px : float, default 40.0
        Scale of the illumination, pixels.
    method : {"divide", "subtract", "none"}, default "divide"
        ``"divide"``: :math:`I / B` — lighting multiplies reflectance, so division makes a joint's
        contrast the same in light and shadow. ``"subtract"``: :math:`I - B + \bar B`, for images
        whose lighting is additive (glare, haze). ``"none"``: the image unchanged.
    clahe : bool, default False
        Then apply contrast-limited adaptive histogram equalisation (OpenCV ``createCLAHE``). Off by
        default: on rock texture it amplifies grain as much as joints.
    clahe_clip_limit : float, default 0.01
        CLAHE clip limit as a fraction of a tile's pixels per grey level (skimage's convention).
    clahe_tile_px : int, default 128
        CLAHE tile side, pixels.

    Returns
    -------
    (H, W) float32 ndarray
        Flattened image; with ``"divide"`` the rock is near 1 and a joint of relative contrast c
        near 1 - c.

    Raises
    ------
    ValueError
        Unknown ``method`` (the message lists the choices) or a non-positive scale.

    References
    ----------
    .. [1] Zuiderveld, K. (1994). Contrast limited adaptive histogram equalization. In Graphics
       Gems IV, 474-485.
    """
    import cv2

    if method not in FLATTEN_METHODS:
        raise ValueError(f"method must be one of {', '.join(FLATTEN_METHODS)}, got {method!r}")
    for value, label in ((line_width_px, "line_width_px"), (sigma_px, "sigma_px")):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{label} must be a finite number > 0 (pixels), got {value!r}")
    image = np.array(grey, dtype=np.float32, copy=True)
    if method != "none":
        background = estimate_background(image, line_width_px=line_width_px, sigma_px=sigma_px)
        if method == "divide":
            floor = max(float(np.percentile(background, 1)) * 0.05, 1e-4)
            image /= np.maximum(background, floor)
        else:
            image += float(background.mean()) - background
    if clahe:
        lo, hi = float(image.min()), float(image.max())
        scaled = np.round((image - lo) / max(hi - lo, 1e-12) * 255).astype(np.uint8)
        h, w = image.shape
        tiles = (max(w // clahe_tile_px, 1), max(h // clahe_tile_px, 1))
        # OpenCV clips each bin at clipLimit * tile pixels / 256: a fraction f of the tile's
        # pixels per grey level is clipLimit = 256 f
        clip = max(clahe_clip_limit * 256.0, 1.0)
        equalised = cv2.createCLAHE(clipLimit=clip, tileGridSize=tiles).apply(scaled)
        image = equalised.astype(np.float32) / 255.0
    return image
