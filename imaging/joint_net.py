"""The convolutional joint detector: a small U-Net's probability of "joint centre line" per pixel,
run with OpenCV's dnn module from an ONNX file (docs/imaging.md §3.6).

The pixel model of :mod:`rockmass.imaging.learned` sees each pixel through 27 hand-made features
and was trained on the package's own rock; on joints drawn over real rock photographs it finds
fewer than half of them (§8.4). This network reads the image itself, over a field of view of about
a hundred pixels, and was trained on joints drawn over many random textures
(:mod:`rockmass.imaging.rock_textures`) besides the field-like and plain synthetic faces, so that
texture is what it learned to ignore. Its input is the face flattened as for the pixel model
(:func:`rockmass.imaging.learned.model_input`), on a log scale (:func:`net_input`); its output a
logit per pixel, turned into a probability by the logistic function. The rest of the chain
(hysteresis, skeleton, linking, trace filters) is the learned detector's.

A model file is an ONNX graph (``.onnx``, opset 13) with one input ``x`` of shape (1, 1, H, W),
H and W multiples of :data:`SIZE_MULTIPLE`, and one output ``logit`` of the same shape; beside it a
JSON file of the same name (``.json``) records how it was trained. The shipped one is
:data:`CNN_MODEL_FILE`, written by :mod:`rockmass.imaging.train_joint_net` (which needs PyTorch; the
detector itself does not).
"""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["CNN_MODEL_FILE", "SIZE_MULTIPLE", "HALO_PX", "MAX_PASS_PIXELS", "ConvModel",
           "net_input", "read_conv_model", "padded_shape", "strip_rows"]

#: The shipped network, inside the installed package (``pixel_model = "cnn"``).
CNN_MODEL_FILE = Path(__file__).resolve().parent / "models" / "joint_cnn.onnx"
#: The network halves its grid three times: its input's sides must be multiples of 8.
SIZE_MULTIPLE = 8
#: An image of more pixels goes through the network in strips of rows. One pass holds the
#: network's intermediate maps for the whole image: over a 4 MP grid a fresh process's peak memory
#: rose by 1.12 GB in one pass, by 0.46 GB in strips of 1.5 MP, whose first pass was also the
#: quicker (1.04 s against 1.23 s; a second pass, its memory already allocated, 0.79 s against
#: 0.63 s: the strips' overlap); strips of 0.5 MP took twice as long
#: (``benchmarks/bench_network_strips.py``, session 27; the chain runs the network once per grid).
MAX_PASS_PIXELS = 1.5e6
#: Rows of context above and below a strip: at least the network's reach (its field of view is
#: 2 x 84 + 1 px: 2 + 4 + 8 + 8 + 16 + 32 + 4 + 2 + 1 px from the convolutions of its levels, 7
#: from the pooling), a multiple of :data:`SIZE_MULTIPLE`.
HALO_PX = 96
#: Gain of the log input: log(I) of a flattened face (I about 1) times this, clipped to ±LOG_CLIP.
LOG_GAIN = 4.0
LOG_CLIP = 8.0
#: Flattened grey levels under this are read as this (the log of 0 is not a number).
LOG_FLOOR = 0.02


def net_input(flat) -> np.ndarray:
    """The network's input from a flattened face I (about 1 on the rock, darker lines below 1):

        x = clip(4 ln max(I, 0.02), -8, 8)

    so a line darker by a share c gives x ≈ -4c whatever the light (float32).

    Examples
    --------
    >>> x = net_input(np.array([[1.0, 0.75, 0.0]]))
    >>> [round(float(v), 3) for v in x[0]]
    [0.0, -1.151, -8.0]
    """
    x = np.log(np.maximum(np.asarray(flat, dtype=np.float32), LOG_FLOOR))
    x *= LOG_GAIN
    return np.clip(x, -LOG_CLIP, LOG_CLIP, out=x)


def padded_shape(shape) -> tuple[int, int]:
    """The shape an input of ``shape`` is padded to before the network: each side up to a
    multiple of :data:`SIZE_MULTIPLE`.

    Examples
    --------
    >>> padded_shape((300, 451))
    (304, 456)
    """
    return tuple(int(side) + (-int(side) % SIZE_MULTIPLE) for side in shape[:2])


def strip_rows(shape, max_pass_pixels: float = MAX_PASS_PIXELS) -> tuple[int, int]:
    """(rows a pass reads, rows of output it gives) for a padded input of ``shape`` (sides
    multiples of :data:`SIZE_MULTIPLE`): every row in one pass when the input has at most
    ``max_pass_pixels`` pixels, else strips of as many rows as fit in ``max_pass_pixels`` (a
    multiple of 8, at least 2 :data:`HALO_PX` + 64), each giving all but its :data:`HALO_PX` rows
    of context above and below.

    Examples
    --------
    >>> strip_rows((800, 1200)), strip_rows((2000, 3000)), strip_rows((2000, 3000), float("inf"))
    ((800, 800), (496, 304), (2000, 2000))
    """
    rows, cols = int(shape[0]), int(shape[1])
    if rows * cols <= max_pass_pixels:
        return rows, rows
    window = int(max_pass_pixels // cols) // SIZE_MULTIPLE * SIZE_MULTIPLE
    window = min(max(window, 2 * HALO_PX + 8 * SIZE_MULTIPLE), rows)
    return window, (rows if window == rows else window - 2 * HALO_PX)


@dataclass(frozen=True, eq=False)
class ConvModel:
    """A convolutional detector read from an ONNX file (module notes).

    Attributes
    ----------
    path : Path
        The ``.onnx`` file.
    info : dict
        How it was trained (the JSON file beside it; empty when there is none).
    """

    path: Path
    info: dict = field(default_factory=dict)
    _local: threading.local = field(default_factory=threading.local, repr=False)

    @property
    def input_stretch(self) -> tuple[float, float] | None:
        """(min_face_spread, max_stretch) its training faces were stretched with, as
        :attr:`rockmass.imaging.learned.PixelModel.input_stretch`."""
        entry = self.info.get("input") or {}
        if "min_face_spread" not in entry:
            return None
        return float(entry["min_face_spread"]), float(entry["max_stretch"])

    def _net(self):
        """This thread's network (an OpenCV ``Net`` keeps the buffers of its last input, so two
        threads must not share one)."""
        net = getattr(self._local, "net", None)
        if net is None:
            import cv2

            net = self._local.net = cv2.dnn.readNetFromONNX(str(self.path))
        return net

    def probability_of(self, flat, *, max_pass_pixels: float = MAX_PASS_PIXELS) -> np.ndarray:
        """Probability map (H, W) float32 in [0, 1] of a :func:`rockmass.imaging.learned.model_input`
        image: the image is padded by reflection to multiples of :data:`SIZE_MULTIPLE`, passed
        through the network (in strips of rows when it has more than ``max_pass_pixels`` pixels,
        each with :data:`HALO_PX` rows of context above and below, so that every output pixel sees
        what it would see in one pass: the same map), cropped back and put through the logistic
        function."""
        import cv2

        x = net_input(flat)
        (h, w), (rows_to, cols_to) = x.shape, padded_shape(x.shape)
        padded = cv2.copyMakeBorder(x, 0, rows_to - h, 0, cols_to - w, cv2.BORDER_REFLECT)
        rows = padded.shape[0]
        window, strip = strip_rows(padded.shape, max_pass_pixels)
        net = self._net()
        logit = np.empty(padded.shape, dtype=np.float32)
        for top in range(0, rows, strip):
            # the strip with its context, shifted inside the image at its ends, so that every
            # pass has one shape (OpenCV plans it once); every start is on the network's
            # coarsest grid (a multiple of 8)
            first = min(max(top - HALO_PX, 0), rows - window)
            net.setInput(np.ascontiguousarray(padded[first:first + window])[None, None])
            out = np.asarray(net.forward(), dtype=np.float32)[0, 0]
            logit[top:top + strip] = out[top - first:top - first + strip]
        from scipy.special import expit  # 1 / (1 + e^-t), without overflow

        return expit(logit[:h, :w]).astype(np.float32, copy=False)


def read_conv_model(path) -> ConvModel:
    """A :class:`ConvModel` of an ``.onnx`` file, with the record of the ``.json`` beside it.

    Raises
    ------
    ValueError
        OpenCV cannot read the file as a network.
    """
    import cv2

    path = Path(path)
    try:
        cv2.dnn.readNetFromONNX(str(path))
    except cv2.error as error:
        raise ValueError(f"{path}: not an ONNX network OpenCV can read ({error})") from error
    record = path.with_suffix(".json")
    info = json.loads(record.read_text()) if record.is_file() else {}
    return ConvModel(path=path, info=info)
