"""The rock face in a photograph: a mask that leaves out lining, sky, machinery and the border.

:func:`face_mask` returns a boolean ``(H, W)`` mask, True on rock, from cheap cues that a geologist
can check against the photo (docs/imaging.md §2.1). :func:`face_mask_cues` returns the same mask
together with each cue on the coarse grid it was computed on, and the share of the image each
cue left out (what ``rockmass extract`` records in ``summary.json``).

Every cue is computed on a copy down-sampled to about :attr:`FaceMaskParams.work_megapixels`
(area averaging) and every length is a fraction of the image's short side, so the mask does not
depend on the camera's resolution; the mask is then up-sampled (nearest neighbour) to the shape
asked for. A 12 MP photograph takes well under 0.1 s on one core
(``benchmarks/bench_imaging_real.py``, section 4).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from types import MappingProxyType
from typing import Mapping

import numpy as np

__all__ = ["FaceMaskParams", "FaceMaskCues", "face_mask", "face_mask_cues", "face_outline_rc",
           "FACE_MASK_MODES"]

#: ``ExtractParams.face_mask`` choices: only the border band, every cue, or no mask.
FACE_MASK_MODES = ("border", "full", "off")


@dataclass(frozen=True)
class FaceMaskParams:
    """Thresholds of the face-mask cues, with the reasoning for each default.

    Lengths are fractions of the image's short side (``_frac``); intensities are on [0, 1] (the
    image's full scale); texture is the gradient magnitude of the log grey level, per pixel of the
    coarse grid.

    Attributes
    ----------
    work_megapixels : float, default 0.25
        Cues are computed on a copy down-sampled to at most this many pixels (about 430 x 580 for
        a 4:3 photo). Lining, sky and machinery are large regions, so this is ample; it keeps a
        12 MP photo well under the 0.3 s budget.
    border_frac : float, default 0.01
        Width of the band along the image border left out, as a fraction of the short side (4 px
        of a 400 px photo; 30 px of a 3000 px one). Vignetting, lens fall-off and the flattening's
        edge effects put dark rims there that the ridge filter reads as joints parallel to the
        border (9 % of the false trace pixels on real faces, issue 22). Traces that cross the
        border are not lost: ``ExtractParams.border_extend_px`` still carries their ends to it.
        Chosen on the rock-face-fractures ``train/`` photos (99, never ``val/``): among widths of
        0.005–0.03 of the short side, 0.01 gave the learned detector its best mean F1 there
        (wider bands cut labelled traces near the border); the sweep is not kept as a benchmark,
        the chosen band's effect on ``val/`` is (``benchmarks/bench_imaging_real.py
        --face-masks``).
    bright_level : float, default 0.97
        Pixels whose brightest channel reaches this share of full scale are over-exposed: sky,
        lamps, specular highlights, reflective plates. Nothing is left there to trace, and the
        steep edge around a clipped patch is the other half of the "edges around bright
        highlights" false traces (49 % of false pixels on real faces, issue 22).
    smooth_ratio : float, default 0.08
        A region is smooth (shotcrete, lining, sky, steel plates) where its texture energy (the RMS
        gradient of the log grey level over a window of ``texture_window_frac``) is below this
        share of the image's 90th percentile of texture energy, i.e. of the rough rock. The log
        makes the cue blind to illumination (a shadowed rock is still rough); the 90th percentile
        assumes that at least a tenth of the photo is rock. On the rock-face-fractures ``train/``
        photos (all rock) 0.2 would mark a median 4 % and up to 50 % of the rock as smooth (smooth
        bedding surfaces); 0.08 marks almost none.
    texture_window_frac : float, default 0.04
        Side of the window the texture energy is averaged over (fraction of the short side).
    min_region_frac : float, default 0.03
        Smooth or coloured regions are left out only when they cover at least this share of the
        image (after an opening): lining, sky and machinery are big; a smooth or mossy patch of rock
        is not.
    saturation_level : float, default 0.55
        Strongly coloured pixels (HSV saturation at least this, brightness at least
        ``saturation_min_value``) are machinery, hoses, signs or vests: painted yellow, orange,
        red or blue. Rock, even iron-stained or moss-covered, rarely exceeds 0.5 (on the ``train/``
        photos the 99th percentile of saturation is at most 0.67 in any image and below 0.49 in
        three quarters of them, and no coloured region reaches ``min_region_frac``).
    saturation_min_value : float, default 0.25
        Saturation is noise in dark pixels; they are never called coloured.
    margin_frac : float, default 0.01
        The rock mask is eroded by this fraction of the short side next to every region left out
        (not the border band, which is a margin itself): the shadowed rim at the edge of a lining,
        a plate or a highlight is where the false traces are.
    keep_component_frac : float, default 0.25
        After clean-up, pieces of rock smaller than this share of the largest piece are dropped (a
        lone island of rough texture on a smooth lining, a gap in machinery).
    """

    work_megapixels: float = 0.25
    border_frac: float = 0.01
    bright_level: float = 0.97
    smooth_ratio: float = 0.08
    texture_window_frac: float = 0.04
    min_region_frac: float = 0.03
    saturation_level: float = 0.55
    saturation_min_value: float = 0.25
    margin_frac: float = 0.01
    keep_component_frac: float = 0.25

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and np.isfinite(value)):
                raise ValueError(f"face mask params.{f.name} must be a finite number, got {value!r}")
        if self.work_megapixels <= 0:
            raise ValueError(f"face mask params.work_megapixels must be > 0, got {self.work_megapixels!r}")
        for name in ("border_frac", "margin_frac", "texture_window_frac"):
            if not 0 <= getattr(self, name) < 0.5:
                raise ValueError(f"face mask params.{name} must be in [0, 0.5) (a fraction of the "
                                 f"short side), got {getattr(self, name)!r}")
        for name in ("bright_level", "smooth_ratio", "min_region_frac", "saturation_level",
                     "saturation_min_value", "keep_component_frac"):
            if not 0 <= getattr(self, name) <= 1:
                raise ValueError(f"face mask params.{name} must be in [0, 1], got {getattr(self, name)!r}")


@dataclass(frozen=True, eq=False)
class FaceMaskCues:
    """A face mask and the cues behind it.

    Attributes
    ----------
    mask : (H, W) ndarray of bool
        True on the rock face, in the shape asked for.
    cues : mapping of str to (h, w) ndarray of bool
        Each cue on the coarse grid, True where it leaves the pixel out: ``border``, ``bright``,
        ``smooth``, ``coloured`` (the last three after their clean-up), and ``margin`` (rock given
        up next to the others) and ``fragments`` (small rock pieces dropped).
    excluded_fraction : mapping of str to float
        Share of the image each cue leaves out (cues overlap, so these may sum to more than the
        total), and ``total``: the share outside ``mask``.
    mode : str
        ``"full"`` or ``"border"`` (only the border band).
    border_px : int
        Width of the border band, pixels of the coarse grid.
    margin_px : float
        Width of the margin, pixels of the coarse grid.
    """

    mask: np.ndarray
    cues: Mapping[str, np.ndarray]
    excluded_fraction: Mapping[str, float]
    mode: str
    border_px: int = 0
    margin_px: float = 0.0

    def summary(self) -> dict:
        """JSON-ready: the mode and the excluded fractions (no arrays)."""
        return {"mode": self.mode, "excluded_fraction": {k: round(float(v), 4)
                                                         for k, v in self.excluded_fraction.items()}}


def _work_shape(shape, work_megapixels: float) -> tuple[int, int]:
    """The coarse grid's (rows, cols) for an image of ``shape``."""
    h, w = int(shape[0]), int(shape[1])
    factor = min(1.0, float(np.sqrt(work_megapixels * 1e6 / (h * w))))
    if factor >= 1.0:
        return h, w
    return max(int(round(h * factor)), 8), max(int(round(w * factor)), 8)


def _work_rgb(image, work_megapixels: float, name: str, *, pixels: bool = True) -> np.ndarray | None:
    """The image on the coarse grid: (h, w, 3) float32 RGB in [0, 1] (grey repeated); with
    ``pixels=False`` only the checks (None)."""
    import cv2

    array = np.asarray(image)
    if array.dtype.kind not in "biuf":
        raise TypeError(f"{name} must hold numbers (grey levels), got dtype {array.dtype}")
    if array.ndim == 3 and array.shape[2] in (3, 4):
        array = array[..., :3]
    elif array.ndim != 2:
        raise ValueError(f"{name} must have shape (H, W), (H, W, 3) or (H, W, 4), got {array.shape}")
    if min(array.shape[:2]) < 1:
        raise ValueError(f"{name} is empty, shape {array.shape}")
    if not pixels:
        return None
    h, w = array.shape[:2]
    if array.dtype not in (np.uint8, np.uint16, np.float32):  # OpenCV resizes these as they are
        scale = 1.0 if array.dtype.kind in "bf" else 1.0 / float(np.iinfo(array.dtype).max)
        array = array.astype(np.float32) * np.float32(scale)
    work = _work_shape((h, w), work_megapixels)
    if work != (h, w):  # area averaging
        array = cv2.resize(np.ascontiguousarray(array), work[::-1], interpolation=cv2.INTER_AREA)
    if array.dtype.kind == "u":
        out = array.astype(np.float32) / np.float32(np.iinfo(array.dtype).max)
    else:
        out = np.asarray(array, dtype=np.float32)
        if not np.isfinite(out).all():
            raise ValueError(f"{name} has non-finite (NaN or inf) pixel values")
    if out.ndim == 2:
        out = np.repeat(out[..., None], 3, axis=2)
    return np.clip(out, 0.0, 1.0)


def _disk(radius: float) -> np.ndarray:
    import cv2

    r = max(int(round(radius)), 1)
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))


def _big_regions(cue: np.ndarray, *, open_px: float, min_area_px: float) -> np.ndarray:
    """Opened, closed, then only the connected pieces of at least ``min_area_px``."""
    import cv2

    m = cue.astype(np.uint8)
    m = cv2.morphologyEx(m, cv2.MORPH_OPEN, _disk(open_px))
    m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, _disk(open_px))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    big = np.zeros(n, dtype=bool)
    big[1:] = stats[1:, cv2.CC_STAT_AREA] >= min_area_px
    return big[labels]


def _checked_params(mode: str, params: FaceMaskParams | None) -> FaceMaskParams:
    """The mode checked, and the params (the defaults when None) checked to be FaceMaskParams."""
    if mode not in ("full", "border"):
        raise ValueError(f"mode must be 'full' or 'border' ('off': do not call), got {mode!r}")
    params = FaceMaskParams() if params is None else params
    if not isinstance(params, FaceMaskParams):
        raise TypeError(f"params must be a FaceMaskParams, got {type(params).__name__}")
    return params


def _out_shape(image, shape_px) -> tuple[int, ...]:
    """The (rows, cols) of the mask returned: ``shape_px``, or the image's when None; checked."""
    full_shape = np.asarray(image).shape[:2]
    out_shape = tuple(int(v) for v in (full_shape if shape_px is None else shape_px))
    if len(out_shape) != 2 or min(out_shape) < 1:
        raise ValueError(f"shape_px must be (rows, cols) >= 1, got {shape_px!r}")
    return out_shape


def _border_band(h: int, w: int, side: float, border_frac: float) -> tuple[np.ndarray, int]:
    """The ``border`` cue on the (h, w) coarse grid, and its width in pixels."""
    border = np.ones((h, w), dtype=bool)
    b = int(round(border_frac * side))
    if b > 0:
        border[b:h - b, b:w - b] = False
    else:
        border[:] = False
    return border, b


def _bright_cue(hsv: np.ndarray, side: float, params: FaceMaskParams) -> np.ndarray:
    """The ``bright`` cue: over-exposed pixels, closed then opened with a disk of 0.5 % of s."""
    import cv2

    bright = hsv[..., 2] >= params.bright_level
    small = 0.005 * side
    bright = cv2.morphologyEx(bright.astype(np.uint8), cv2.MORPH_CLOSE, _disk(small))
    return cv2.morphologyEx(bright, cv2.MORPH_OPEN, _disk(small)).astype(bool)


def _texture_energy(rgb: np.ndarray, side: float, params: FaceMaskParams) -> tuple[np.ndarray, int]:
    """RMS gradient of the log luma over the texture window, and the window's side in pixels."""
    import cv2

    grey = rgb @ np.array([0.299, 0.587, 0.114], dtype=np.float32)
    log = cv2.GaussianBlur(np.log(grey + np.float32(0.02)), (0, 0), 1.0)
    gx = cv2.Sobel(log, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(log, cv2.CV_32F, 0, 1, ksize=3)
    win = max(int(round(params.texture_window_frac * side)) | 1, 3)
    # the box filter's running sums can dip a hair below 0 on flat ground
    energy = np.sqrt(np.maximum(cv2.boxFilter((gx * gx + gy * gy) / 64.0, -1, (win, win)), 0.0))
    return energy, win


def _smooth_cue(energy: np.ndarray, win: int, border: np.ndarray, params: FaceMaskParams, *,
                open_px: float, min_area: float) -> np.ndarray:
    """The ``smooth`` cue: big regions of low texture energy, dilated by half the window."""
    import cv2

    inner = energy[~border] if (~border).any() else energy.ravel()
    reference = float(np.percentile(inner, 90))
    smooth = _big_regions(energy < params.smooth_ratio * reference, open_px=open_px,
                          min_area_px=min_area) if reference > 0 else np.zeros(border.shape, bool)
    if smooth.any():  # the window average carries the rock's texture win / 2 into the smooth
        smooth = cv2.dilate(smooth.astype(np.uint8), _disk(win / 2)).astype(bool)
    return smooth


def _coloured_cue(hsv: np.ndarray, params: FaceMaskParams, *, open_px: float,
                  min_area: float) -> np.ndarray:
    """The ``coloured`` cue: big regions of saturated, not dark, pixels."""
    coloured = (hsv[..., 1] >= params.saturation_level) & (hsv[..., 2] >= params.saturation_min_value)
    return _big_regions(coloured, open_px=open_px, min_area_px=min_area)


def _with_margin(excluded: np.ndarray, margin_px: float) -> tuple[np.ndarray, np.ndarray]:
    """``excluded`` dilated by ``margin_px`` (when at least half a pixel), and the rim added."""
    import cv2

    if margin_px >= 0.5 and excluded.any():
        grown = cv2.dilate(excluded.astype(np.uint8), _disk(margin_px)).astype(bool)
    else:
        grown = excluded
    return grown, grown & ~excluded


def _big_rock_pieces(rock: np.ndarray, keep_component_frac: float) -> np.ndarray:
    """The pieces of ``rock`` of at least ``keep_component_frac`` of the largest one."""
    import cv2

    n, labels, stats, _ = cv2.connectedComponentsWithStats(rock.astype(np.uint8), connectivity=8)
    if n > 1:
        sizes = stats[1:, cv2.CC_STAT_AREA]
        keep = np.zeros(n, dtype=bool)
        keep[1:] = sizes >= keep_component_frac * sizes.max()
        return keep[labels]
    return rock


def _resized_mask(kept: np.ndarray, border: np.ndarray, out_shape: tuple[int, ...]) -> np.ndarray:
    """The kept rock (or, if none, everything inside the border band) on the ``out_shape`` grid."""
    import cv2

    if not kept.any():  # nothing looks like rock: fall back to the border band alone
        kept = ~border if (~border).any() else np.ones(border.shape, dtype=bool)
    if kept.shape != out_shape:
        return cv2.resize(kept.astype(np.uint8), (out_shape[1], out_shape[0]),
                          interpolation=cv2.INTER_NEAREST).astype(bool)
    return kept


def _excluded_fractions(cues: Mapping[str, np.ndarray], mask: np.ndarray) -> dict[str, float]:
    """Share of the image each cue leaves out, and ``total``: the share outside ``mask``."""
    fractions = {k: float(v.mean()) for k, v in cues.items()}
    fractions["total"] = float(1.0 - mask.mean())
    return fractions


def face_mask_cues(image, *, shape_px: tuple[int, int] | None = None, mode: str = "full",
                   params: FaceMaskParams | None = None, name: str = "image") -> FaceMaskCues:
    """The rock-face mask of a photograph, with the cues behind it.

    Parameters
    ----------
    image : (H, W), (H, W, 3) or (H, W, 4) array_like
        The photograph: grey, RGB or RGBA (alpha ignored); uint8, uint16, or float in [0, 1].
        Never modified. Grey images get no colour cue (saturation is 0).
    shape_px : (rows, cols), optional
        Shape of the mask returned (the extraction's working grid, say); default the image's.
    mode : {"full", "border"}, default "full"
        ``"border"``: only the border band (no other cue is computed).
    params : FaceMaskParams, optional
        Thresholds; default ``FaceMaskParams()`` (each documented there, with its reasoning).
    name : str, default "image"
        Name used in error messages.

    Returns
    -------
    FaceMaskCues

    Raises
    ------
    ValueError
        A bad shape, mode or parameter (the message names it), or non-finite pixel values.
    TypeError
        A non-numeric image.

    Notes
    -----
    On a coarse copy of the image (short side :math:`s` pixels):

    1. ``border``: the band within ``border_frac`` · s of the image edge.
    2. ``bright``: max(R, G, B) >= ``bright_level`` (clipped highlights, sky, lamps).
    3. ``smooth``: texture energy :math:`E = \\sqrt{\\overline{|\\nabla \\log(Y + 0.02)|^2}}`
       (Y the BT.601 luma, gradient by 3x3 Sobel after a 1 px Gaussian, mean over a square window
       of ``texture_window_frac`` · s) below ``smooth_ratio`` times its 90th percentile.
    4. ``coloured``: HSV saturation >= ``saturation_level`` and value >= ``saturation_min_value``.

    ``bright`` is closed and opened with a disk of 0.5 % of s; ``smooth`` and ``coloured`` are
    opened and closed with a disk of 1 % of s and kept only as connected pieces of at least
    ``min_region_frac`` of the image; ``smooth`` is then dilated by half the texture window, by
    which the window's average carries the rock's texture across the boundary. The union of the
    three is dilated by ``margin_frac`` · s (``margin``); the rest of the image, less the border
    band, is the rock, of which the pieces of at least ``keep_component_frac`` of the largest are
    kept (``fragments``: the others). If no rock
    is left (a photo of a wall), the mask falls back to everything inside the border band, so the
    extraction still runs; ``excluded_fraction["total"]`` then says what happened.

    The cues are deliberately plain: each is one threshold on a quantity that can be shown on the
    photo. They do not know what rock is; a smooth, pale bedding plane covering a large part of the
    photo can be taken for lining (turn the cue off with ``smooth_ratio=0``, or give a ROI).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> img = np.full((200, 300), 0.5, dtype=np.float32)
    >>> img[:, :150] = rng.uniform(0.2, 0.8, (200, 150))   # rough "rock" on the left
    >>> cues = face_mask_cues(img)
    >>> bool(cues.mask[100, 50]), bool(cues.mask[100, 250])   # rock kept, flat panel left out
    (True, False)
    """
    import cv2

    # working copy: checks, and the photo down-sampled to the coarse grid ("full" only: the
    # border band needs no pixels)
    params = _checked_params(mode, params)
    rgb = _work_rgb(image, params.work_megapixels, name, pixels=mode == "full")
    out_shape = _out_shape(image, shape_px)
    h, w = _work_shape(np.asarray(image).shape[:2], params.work_megapixels)
    side = float(min(h, w))

    border, b = _border_band(h, w, side, params.border_frac)
    cues: dict[str, np.ndarray] = {"border": border}
    excluded = np.zeros((h, w), dtype=bool)
    if mode == "full":
        hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)  # float input: S and V = max(R, G, B) in [0, 1]
        bright = _bright_cue(hsv, side, params)
        energy, win = _texture_energy(rgb, side, params)
        open_px, min_area = 0.01 * side, params.min_region_frac * float(h * w)
        smooth = _smooth_cue(energy, win, border, params, open_px=open_px, min_area=min_area)
        coloured = _coloured_cue(hsv, params, open_px=open_px, min_area=min_area)
        cues.update(bright=bright, smooth=smooth, coloured=coloured)
        excluded, cues["margin"] = _with_margin(bright | smooth | coloured, params.margin_frac * side)

    rock = ~excluded & ~border
    kept = _big_rock_pieces(rock, params.keep_component_frac)
    cues["fragments"] = rock & ~kept
    mask = _resized_mask(kept, border, out_shape)
    return FaceMaskCues(mask=mask, cues=MappingProxyType(cues),
                        excluded_fraction=MappingProxyType(_excluded_fractions(cues, mask)),
                        mode=mode, border_px=b, margin_px=params.margin_frac * side)


def face_mask(image, *, shape_px: tuple[int, int] | None = None, mode: str = "full",
              params: FaceMaskParams | None = None) -> np.ndarray:
    """Boolean mask of the rock face in a photograph: True on rock.

    Leaves out the image border, over-exposed regions (sky, highlights), large smooth regions
    (shotcrete, lining, plates, sky) and large strongly coloured regions (machinery), each with a
    margin; :func:`face_mask_cues` documents the cues and returns them too, and
    :class:`FaceMaskParams` gives each threshold with its reasoning.

    Parameters
    ----------
    image : (H, W), (H, W, 3) or (H, W, 4) array_like
        The photograph (grey, RGB or RGBA; uint8, uint16, or float in [0, 1]); never modified.
    shape_px : (rows, cols), optional
        Shape of the mask; default the image's.
    mode : {"full", "border"}, default "full"
    params : FaceMaskParams, optional

    Returns
    -------
    (rows, cols) ndarray of bool

    Examples
    --------
    >>> img = np.random.default_rng(1).uniform(0.2, 0.8, (100, 100))
    >>> m = face_mask(img)
    >>> bool(m[50, 50]), bool(m[0, 0]), m.shape
    (True, False, (100, 100))
    """
    return face_mask_cues(image, shape_px=shape_px, mode=mode, params=params).mask


def face_outline_rc(cues: FaceMaskCues, shape_px: tuple[int, int]) -> np.ndarray | None:
    """Outline of the rock face found by :func:`face_mask_cues`, as a sampling window.

    The face is the coarse grid less the ``bright``, ``smooth`` and ``coloured`` cues (not the
    border band nor the margin: traces are carried to the image border, and the margin only keeps
    candidates away from edges); of its pieces, the one that holds most of the mask. Its outer
    contour (holes, such as highlights inside the rock, are not subtracted) is simplified by
    one coarse pixel and scaled to ``shape_px``. Slivers thinner than twice the margin are opened
    away first (the mask has none: its margin removed them).

    Parameters
    ----------
    cues : FaceMaskCues
    shape_px : (rows, cols)
        Grid of the returned vertices (the input image, say).

    Returns
    -------
    (k, 2) ndarray of float64 or None
        Polygon vertices (row, col) in ``shape_px`` pixels, or None when the cues left nothing out
        but the border band (the window is then the image rectangle).
    """
    import cv2

    parts = [cues.cues[k] for k in ("bright", "smooth", "coloured") if k in cues.cues]
    if not parts or not any(p.any() for p in parts):
        return None
    face = ~np.logical_or.reduce(parts)
    h, w = face.shape
    # slivers thinner than the margin (between two left-out regions) are not part of the face
    margin = max(cues.margin_px, 1.0)
    face = cv2.morphologyEx(face.astype(np.uint8), cv2.MORPH_OPEN, _disk(margin)).astype(bool)
    n, labels = cv2.connectedComponents(face.astype(np.uint8), connectivity=8)
    if n <= 1:
        return None
    small = cv2.resize(cues.mask.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST)
    overlap = np.bincount(labels[small.astype(bool)], minlength=n)
    overlap[0] = 0
    piece = (labels == int(np.argmax(overlap))).astype(np.uint8)
    contours, _ = cv2.findContours(piece, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    ring = cv2.approxPolyDP(max(contours, key=cv2.contourArea), 1.0, True)[:, 0, :]
    if ring.shape[0] < 3:
        return None
    # contour pixels (x = col, y = row) on the coarse grid -> pixel-edge coordinates -> shape_px
    # vertices on the grid's first or last row / column go to the image edge itself
    rows = (ring[:, 1] + 0.5) * shape_px[0] / h - 0.5
    cols = (ring[:, 0] + 0.5) * shape_px[1] / w - 0.5
    rows[ring[:, 1] == 0], rows[ring[:, 1] == h - 1] = -0.5, shape_px[0] - 0.5
    cols[ring[:, 0] == 0], cols[ring[:, 0] == w - 1] = -0.5, shape_px[1] - 0.5
    return np.column_stack([rows, cols]).astype(np.float64)
