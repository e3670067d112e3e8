"""Hand-traced joint labels of a photograph: read a label image as a mask and its centre lines.

Two label formats are read, the ones public labelled sets use:

- *painted*: the traces painted in pure red on anything else (``R > 128``, ``G < 100``,
  ``B < 100``), as in the rock-face-fractures set of ``../shared/data`` (whose label files also
  carry a 1-px white frame that is not a label);
- *mask*: white (or any bright value, grey > 127) traces on black, in a grey or colour image.

An image with any red-painted pixel is read as painted, else as a mask. The centre lines are the
mask thinned to one pixel (Zhang & Suen 1984, :func:`rockmass.imaging.skeleton_graph.skeletonize`),
which is how the benchmarks score against labels and how :mod:`rockmass.imaging.train_pixel_model`
samples positives from a user's own labelled photographs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["label_mask", "label_centre_lines", "photo_centre_lines", "labelled_pairs"]

#: Image file suffixes read as photographs when pairing a folder of photos with its labels.
PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".bmp")


def label_mask(label) -> np.ndarray:
    """Bool mask of the traces of a label image (a path, or an (H, W) / (H, W, 3) uint8 array in
    RGB order). Images of 16 bits are read at the same levels on 8; an alpha channel is ignored;
    a grey mask of 0 and 1 is read as one of 0 and 255.

    Examples
    --------
    >>> rgb = np.zeros((5, 5, 3), np.uint8); rgb[2, :, 0] = 255; rgb[0, :] = 255  # red + white
    >>> label_mask(rgb).sum(), label_mask(rgb)[2].all()
    (np.int64(5), np.True_)
    >>> label_mask(np.where(np.eye(4, dtype=bool), 255, 0).astype(np.uint8)).sum()
    np.int64(4)
    """
    name = ""
    if isinstance(label, (str, Path)):
        import cv2

        name = f"{label}: "
        stored = cv2.imread(str(label), cv2.IMREAD_UNCHANGED)
        if stored is None:
            raise OSError(f"{label}: cannot read the label image")
        label = stored[..., 2::-1] if stored.ndim == 3 else stored  # BGR(A) -> RGB
    array = np.asarray(label)
    if array.ndim == 3 and array.shape[2] == 2:  # grey and alpha: the grey
        array = array[..., 0]
    if array.dtype == np.uint16:  # 16-bit masks: the same levels on 8 bits
        array = (array // 257).astype(np.uint8)
    if array.dtype != np.uint8 or array.ndim not in (2, 3):
        raise ValueError(f"{name}a label image must be a grey or colour image of 8 or 16 bits, "
                         f"got {array.dtype} of shape {array.shape}")
    if array.ndim == 3:
        red = (array[..., 0] > 128) & (array[..., 1] < 100) & (array[..., 2] < 100)
        if red.any():
            return red
        array = array[..., :3].mean(axis=2)
    if array.max(initial=0) == 1:  # a 0/1 mask, as segmentation data sets store them
        return array > 0
    return array > 127


def label_centre_lines(label) -> np.ndarray:
    """One-pixel centre lines (bool) of :func:`label_mask`."""
    from .skeleton_graph import skeletonize

    return skeletonize(label_mask(label))


def photo_centre_lines(label, photo, photo_shape) -> np.ndarray:
    """:func:`label_centre_lines` of the label of ``photo`` (a path, for the message), whose image
    is ``photo_shape`` (rows, cols, ...) pixels.

    Raises
    ------
    ValueError
        The label's size differs from the photograph's (the message names both files).
    """
    lines = label_centre_lines(label)
    if lines.shape != tuple(photo_shape[:2]):
        raise ValueError(f"{label}: label is {lines.shape[1]} x {lines.shape[0]} px, its photo "
                         f"{Path(photo).name} {photo_shape[1]} x {photo_shape[0]} px")
    return lines


def labelled_pairs(photos_dir, labels_dir) -> list[tuple[Path, Path]]:
    """(photo, label) paths: every photo of ``photos_dir`` whose stem has a label file of any
    :data:`PHOTO_SUFFIXES` suffix in ``labels_dir``, sorted by name.

    Raises
    ------
    FileNotFoundError
        A folder is missing, holds no image, or no photo has a label.
    ValueError
        The labels are in the photos' folder, or two labels have one name (``a.png``, ``a.tif``).
    OSError
        A folder cannot be listed.
    """
    photos_dir, labels_dir = Path(photos_dir), Path(labels_dir)
    for folder, what in ((photos_dir, "photos"), (labels_dir, "labels")):
        if not folder.is_dir():
            raise FileNotFoundError(f"{folder}: no such folder of {what}")
    if photos_dir.resolve() == labels_dir.resolve():
        raise ValueError(f"{labels_dir}: the labels are in the photos' folder; put them in a folder "
                         "of their own, under the photos' file names")
    labels: dict[str, Path] = {}
    for path in sorted(_images(labels_dir)):
        if path.stem in labels:
            raise ValueError(f"{labels_dir}: two labels of one name, {labels[path.stem].name} and "
                             f"{path.name}: keep one")
        labels[path.stem] = path
    photos = sorted(_images(photos_dir))
    suffixes = ", ".join(sorted(PHOTO_SUFFIXES))
    for folder, found, what in ((photos_dir, photos, "photo"), (labels_dir, labels, "label")):
        if not found:
            raise FileNotFoundError(f"{folder}: no {what} in the folder (image files: {suffixes})")
    pairs = [(p, labels[p.stem]) for p in photos if p.stem in labels]
    if not pairs:
        raise FileNotFoundError(f"{photos_dir}: no photo has a label of the same name in {labels_dir}")
    return pairs


def _images(folder: Path) -> list[Path]:
    """The files of ``folder`` with an image suffix (:data:`PHOTO_SUFFIXES`)."""
    return [p for p in folder.iterdir() if p.suffix.lower() in PHOTO_SUFFIXES and p.is_file()]
