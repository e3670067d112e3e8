"""The learned joint detector: small multilayer perceptrons giving, per pixel, the probability of
lying on a joint's centre line (docs/imaging.md §3.1).

Stage 1 reads the features of :func:`rockmass.imaging.features.pixel_features`; stage 2 reads the
same features and the context of stage 1's probability map
(:func:`rockmass.imaging.features.context_features`: is the pixel on a long run of likely pixels?),
as in auto-context (Tu & Bai 2010). Each stage standardises its inputs by the training set's mean
and standard deviation, clips them to ±6, and applies two hidden layers of rectified linear units
and a logistic output,

    p = σ(w₃ᵀ relu(W₂ relu(W₁ z + b₁) + b₂) + b₃),   σ(t) = 1 / (1 + e^{−t})          (3.2)

The stages are trained by :mod:`rockmass.imaging.train_pixel_model` on synthetic faces only
(:func:`rockmass.imaging.synthetic_field.field_face` and
:func:`rockmass.imaging.synthetic.synthetic_face`). The weights ship inside the package as a NumPy
``.npz`` file (:data:`MODEL_FILE`, about 8 kB) read with ``allow_pickle=False``; nothing is
downloaded. Inference is NumPy matrix products over blocks of pixels small enough to stay in the
processor's cache (:meth:`Stage.predict`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from .features import CONTEXT_NAMES, FEATURE_NAMES, context_features, pixel_features
from .joint_net import CNN_MODEL_FILE

__all__ = ["MODEL_FILE", "SHIPPED_MODELS", "MODEL_LINE_WIDTH_PX", "MIN_SPREAD", "MAX_STRETCH", "Stage", "PixelModel",
           "load_model", "model_record", "flattened", "model_input", "stretch_gain",
           "stretch_flat_face", "joint_probability"]

#: The shipped model, inside the installed package.
MODEL_FILE = Path(__file__).resolve().parent / "models" / "joint_pixel_mlp.npz"
#: Widest dark line kept out of the illumination estimate before the features (pixels).
MODEL_LINE_WIDTH_PX = 12.0
#: Standardised inputs are clipped to ± this many standard deviations.
CLIP_SD = 6.0
#: A flattened face whose relative spread (1.4826 MAD / median) is under this is stretched to it
#: before the features (:func:`stretch_flat_face`): the plain synthetic "moderate" faces' spread,
#: the flattest faces on which the model is measured. The shipped model's training faces spread
#: 0.100-0.597, the real ``train/`` photographs 0.057-0.394 (``bench_imaging_real.py
#: --spreads-only``).
MIN_SPREAD = 0.075
#: The stretch is at most this many times: a face flatter than MIN_SPREAD / MAX_STRETCH holds too
#: few grey levels to be worth stretching further.
MAX_STRETCH = 10.0


@dataclass(frozen=True, eq=False)
class Stage:
    """One perceptron of eq. (3.2).

    Attributes
    ----------
    mean, std : (F,) float32 ndarray
        Input standardisation.
    weights, biases : tuple of ndarrays
        Layer k maps ``x`` to ``x @ weights[k] + biases[k]``; ReLU between layers, logistic at the end.
    """

    mean: np.ndarray
    std: np.ndarray
    weights: tuple
    biases: tuple

    def __post_init__(self):
        if not np.all(np.asarray(self.std) > 0):  # also refuses NaN
            raise ValueError("a stage's input standard deviations must all be > 0")

    def predict(self, columns: np.ndarray, *, block: int = 512) -> np.ndarray:
        """Probability (float32, shape (N,)) for each column of (F, N) inputs.

        Columns, not rows: the features of an image come as (F, H, W) maps, and
        ``features.reshape(F, -1)`` is then a view; a (N, F) row array is passed as ``x.T``.
        The columns go through in blocks of ``block``: 512 keeps a block's layers (2 x 32 x 512
        float32, 128 kB) in the processor's cache. The layers are a numba kernel's
        (:func:`rockmass.imaging._mlp_kernel.mlp_forward`), not NumPy's matrix product, whose
        BLAS threads spin on the core "auto"'s ridge chain runs on
        (``benchmarks/bench_pixel_inference.py`` times both, alone and beside that chain).
        """
        from ._mlp_kernel import mlp_forward

        x = np.ascontiguousarray(columns, dtype=np.float32)
        if x.ndim != 2 or x.shape[0] != self.mean.size:
            raise ValueError(f"inputs must be ({self.mean.size}, N) columns, got shape {x.shape}")
        if block < 1:
            raise ValueError(f"block must be at least 1 column, got {block}")
        low, high, mean, weights, biases = self._folded
        out = np.empty(x.shape[1], dtype=np.float32)
        mlp_forward(x, low[:, 0], high[:, 0], mean[:, 0],
                    np.concatenate([w.ravel() for w in weights]),
                    np.concatenate([c.ravel() for c in biases]),
                    np.array([self.mean.size, *(w.shape[0] for w in weights)], dtype=np.int64),
                    int(block), out)
        return out

    @cached_property
    def _folded(self):
        """Eq. (3.2) with the division by s folded into the first layer: clipping z = (x − m) / s
        to ±CLIP_SD is clipping x to m ± CLIP_SD·s, and W₁ᵀz = (W₁ / s)ᵀ(x − m). (The mean is
        still subtracted from the inputs, not folded into the bias, which would cancel digits
        when |m| ≫ s.) Returns (low, high, mean column, transposed weights, bias columns),
        float32."""
        mean, std = self.mean.astype(np.float64), self.std.astype(np.float64)
        first = self.weights[0].astype(np.float64) / std[:, None]
        weights = [first.T] + [w.T for w in self.weights[1:]]
        return ((mean - CLIP_SD * std).astype(np.float32)[:, None],
                (mean + CLIP_SD * std).astype(np.float32)[:, None],
                mean.astype(np.float32)[:, None],
                tuple(np.ascontiguousarray(w, dtype=np.float32) for w in weights),
                tuple(np.asarray(b, dtype=np.float32)[:, None] for b in self.biases))


@dataclass(frozen=True, eq=False)
class PixelModel:
    """A trained detector: one or two :class:`Stage` s (see the module notes).

    Attributes
    ----------
    stages : tuple of Stage
        Stage 1 reads the pixel features; a stage 2 reads them and the context of stage 1.
    feature_names : tuple of str
        The inputs of the last stage, in order (pixel features, then context features).
    info : dict
        How the model was trained (command, seeds, faces, samples, time).
    """

    stages: tuple
    feature_names: tuple
    info: dict = field(default_factory=dict)

    @property
    def input_stretch(self) -> tuple[float, float] | None:
        """(min_face_spread, max_stretch) of the stretch its training faces went through
        (:func:`stretch_flat_face`, recorded in ``info["input"]`` by
        :mod:`rockmass.imaging.train_pixel_model`); None for a model file that does not record it
        (trained before rockmass recorded it)."""
        entry = self.info.get("input") or {}
        if "min_face_spread" not in entry:
            return None
        return float(entry["min_face_spread"]), float(entry.get("max_stretch", MAX_STRETCH))

    def probability(self, features: np.ndarray) -> np.ndarray:
        """Joint probability map (H, W) from the (F, H, W) pixel features of an image."""
        shape = features.shape[1:]
        p = self.stages[0].predict(features.reshape(features.shape[0], -1)).reshape(shape)
        for stage in self.stages[1:]:
            both = np.concatenate([features, context_features(p)])
            p = stage.predict(both.reshape(both.shape[0], -1)).reshape(shape)
        return p

    def save(self, path) -> Path:
        """Write the model as a compressed ``.npz`` file (no pickled objects)."""
        import json

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {"feature_names": np.array(self.feature_names),
                  "info": np.array(json.dumps(self.info, sort_keys=True))}
        for i, stage in enumerate(self.stages):
            arrays[f"s{i}_mean"], arrays[f"s{i}_std"] = stage.mean, stage.std
            for k, (w, b) in enumerate(zip(stage.weights, stage.biases)):
                arrays[f"s{i}_w{k}"], arrays[f"s{i}_b{k}"] = w.astype(np.float32), b.astype(np.float32)
        from ..dfn.atomic import atomic_open

        with atomic_open(path, "wb") as handle:  # all or nothing
            np.savez_compressed(handle, **arrays)
        return path


_CACHE: dict[str, PixelModel] = {}
_RECORDS: dict[str, dict] = {}


def _read_stage(data, i):
    n_layers = sum(1 for name in data.files if name.startswith(f"s{i}_w"))
    return Stage(mean=data[f"s{i}_mean"].astype(np.float32), std=data[f"s{i}_std"].astype(np.float32),
                 weights=tuple(data[f"s{i}_w{k}"].astype(np.float32) for k in range(n_layers)),
                 biases=tuple(data[f"s{i}_b{k}"].astype(np.float32) for k in range(n_layers)))


def load_model(path=None):
    """Read a model file (default: the shipped :data:`MODEL_FILE`); cached per path. A ``.npz``
    file is a :class:`PixelModel`, an ``.onnx`` file a convolutional detector
    (:class:`rockmass.imaging.joint_net.ConvModel`, docs/imaging.md §3.6).

    Raises
    ------
    FileNotFoundError
        The file is missing (a broken install when it is the shipped one).
    ValueError
        The file's inputs differ from the features this rockmass computes.
    """
    import json

    key = _resolved(path)
    if key in _CACHE:
        return _CACHE[key]
    if Path(key).suffix.lower() == ".onnx":  # the convolutional detector (§3.6)
        if not Path(key).is_file():
            raise FileNotFoundError(f"{path or key}: no such network file (params.pixel_model; "
                                    "train one with python -m rockmass.imaging.train_joint_net)")
        from .joint_net import read_conv_model

        _CACHE[key] = read_conv_model(key)
        return _CACHE[key]
    if not Path(key).is_file():
        if path is not None and Path(key) != MODEL_FILE.resolve():
            raise FileNotFoundError(f"{path}: no such model file (params.pixel_model; train one with "
                                    "python -m rockmass.imaging.train_pixel_model)")
        raise FileNotFoundError(f"{key}: the learned detector's model file is missing (it ships with "
                                "rockmass; reinstall, or train one with python -m "
                                "rockmass.imaging.train_pixel_model)")
    import zipfile

    try:
        with np.load(key, allow_pickle=False) as data:
            n_stages = sum(1 for name in data.files if name.endswith("_mean"))
            model = PixelModel(stages=tuple(_read_stage(data, i) for i in range(n_stages)),
                               feature_names=tuple(str(s) for s in data["feature_names"]),
                               info=json.loads(str(data["info"])))
    except (ValueError, KeyError, OSError, zipfile.BadZipFile, TypeError) as error:
        raise ValueError(f"{key}: not a pixel model written by rockmass.imaging.train_pixel_model "
                         f"({type(error).__name__}: {error})") from error
    expected = FEATURE_NAMES + (CONTEXT_NAMES if n_stages > 1 else ())
    if model.feature_names != expected:
        raise ValueError(f"{key}: the model was trained on other features ({len(model.feature_names)}"
                         f" named) than this rockmass computes ({len(expected)}); retrain it")
    _CACHE[key] = model
    return model


#: Names of the shipped models a ``pixel_model`` setting may give instead of a path.
SHIPPED_MODELS = {"mlp": MODEL_FILE,
                  "cnn": CNN_MODEL_FILE}


def _resolved(path) -> str:
    """The absolute path of a model file (None: the shipped pixel model; "mlp" or "cnn": a shipped
    model, :data:`SHIPPED_MODELS`), the key of the caches."""
    if isinstance(path, str) and path in SHIPPED_MODELS:
        path = SHIPPED_MODELS[path]
    return str(Path(path or MODEL_FILE).resolve())


def model_record(path=None) -> dict:
    """Which model a result came from, for its summary: ``file`` (resolved path), ``shipped``
    (bool: the model of the package), ``sha256`` of the file, ``trained_on`` (the ``data`` entry
    of its ``info``) and ``input_stretch`` (``min_face_spread`` and ``max_stretch`` of the stretch
    its training faces went through, :attr:`PixelModel.input_stretch`; None when not recorded) and
    ``back_end`` (the settings chosen for it by ``train_pixel_model --choose-back-end``, docs/imaging.md
    §3.2; None when not chosen).
    The model is loaded (and checked) as :func:`load_model` does; the file is hashed once per
    path, like the model it caches."""
    import hashlib

    from .site_back_end import chosen_settings

    key = _resolved(path)
    if key not in _RECORDS:
        model = load_model(path)
        _RECORDS[key] = {"file": key, "shipped": key in {_resolved(name) for name in SHIPPED_MODELS},
                         "sha256": hashlib.sha256(Path(key).read_bytes()).hexdigest(),
                         "trained_on": model.info.get("data"),
                         "input_stretch": None if model.input_stretch is None
                         else dict(zip(("min_face_spread", "max_stretch"), model.input_stretch)),
                         "back_end": chosen_settings(model.info)}
    return dict(_RECORDS[key])


def flattened(grey, *, background_sigma_px: float = 40.0) -> np.ndarray:
    """The face divided by its background, with dark lines up to :data:`MODEL_LINE_WIDTH_PX`
    kept out of it (docs/imaging.md §2, eq. (2.1)): what trace contrasts are measured on."""
    from .enhance import flatten_illumination

    return flatten_illumination(grey, line_width_px=MODEL_LINE_WIDTH_PX, sigma_px=background_sigma_px,
                                method="divide")


def model_input(grey, *, background_sigma_px: float = 40.0,
                min_spread: float = MIN_SPREAD) -> np.ndarray:
    """The image the features are computed on: :func:`flattened`, stretched when the face is
    flatter than ``min_spread`` (:func:`stretch_flat_face`; 0: never). Training reads it so; the
    extraction chain does the same in two steps, to keep the unstretched face for contrasts."""
    return stretch_flat_face(flattened(grey, background_sigma_px=background_sigma_px),
                             min_spread=min_spread)[0]


def stretch_gain(spread: float, min_spread: float = MIN_SPREAD,
                 max_stretch: float = MAX_STRETCH) -> float:
    """The factor g = min(max(1, min_spread / s), max_stretch) of :func:`stretch_flat_face` for a
    face of relative spread ``spread`` (1 for a face of no spread).

    Examples
    --------
    >>> round(stretch_gain(0.025), 6), stretch_gain(0.2), stretch_gain(0.001), stretch_gain(0.0)
    (3.0, 1.0, 10.0, 1.0)
    """
    if not spread > 0:
        return 1.0
    return min(max(1.0, min_spread / spread), max_stretch)


def stretch_flat_face(flat, *, min_spread: float = MIN_SPREAD, max_stretch: float = MAX_STRETCH,
                      mask=None, levels=None) -> tuple[np.ndarray, float, float]:
    r"""A flattened face of low contrast stretched about its median to the spread ``min_spread``.

    With m the median of the flattened image I and :math:`s = 1.4826\,\mathrm{MAD}(I) / m` its
    relative spread (robust standard deviation over median, over the face ``mask`` when given;
    :func:`rockmass.imaging.vectorize.face_levels`, or its result given as ``levels``),

    .. math:: I' = \max\bigl(0,\ m + g\,(I - m)\bigr),
              \qquad g = \min\bigl(\max(1, s_{min} / s),\ g_{max}\bigr),

    so a face already as contrasted as ``min_spread`` is returned as it is (g = 1), and so is a
    face with no spread at all (a uniform grey but for its lines). The pixel
    model's features respond to grey-level differences, not ratios: the same face photographed
    in flatter light, every difference from the median smaller by a factor f, gives weaker
    responses and, below the spreads the model was trained on, probabilities too low to reach
    its thresholds (docs/imaging.md §3.1). The stretch undoes f up to ``max_stretch``.

    Returns
    -------
    (image, g, s)
        With g > 1 a new float array (float32 for float32 input); with g = 1 ``flat`` itself.
        ``flat`` is never modified. s is the face's relative spread before the stretch.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> face = 1.0 + 0.1 * rng.standard_normal((50, 50))
    >>> dim = 1.0 + 0.02 * (face - 1.0) / 0.1
    >>> out, gain, spread = stretch_flat_face(dim.astype(np.float32))
    >>> round(gain, 1), round(spread, 3)
    (3.7, 0.02)
    >>> spread = 1.4826 * np.median(np.abs(out - np.median(out))) / np.median(out)
    >>> round(float(spread), 3)
    0.075
    >>> stretch_flat_face(face.astype(np.float32))[1]
    1.0
    """
    if not max_stretch >= 1:
        raise ValueError(f"max_stretch must be >= 1 (1: never stretch), got {max_stretch!r}")
    from .vectorize import face_levels

    values = np.asarray(flat)
    median, spread, _ = face_levels(values, mask=mask) if levels is None else levels
    if not (median > 0 and spread > 0):  # e.g. a uniform face but for its lines: not flat light
        return values, 1.0, spread
    gain = stretch_gain(spread, min_spread, max_stretch)
    if gain == 1.0:
        return values, 1.0, spread
    kind = values.dtype if values.dtype.kind == "f" else np.float64
    stretched = values.astype(kind)  # a copy: the caller's image is not changed
    stretched -= median
    stretched *= gain
    stretched += median
    return np.maximum(stretched, 0.0, out=stretched), float(gain), spread


def joint_probability(flat, model=None) -> np.ndarray:
    """Probability map (H, W) float32 in [0, 1] of joint centre lines in a :func:`model_input` image,
    by a :class:`PixelModel` (default: the shipped one) or a convolutional detector
    (:class:`rockmass.imaging.joint_net.ConvModel`).

    Examples
    --------
    >>> img = np.ones((64, 64), np.float32); img[:, 30:33] = 0.5
    >>> p = joint_probability(img)
    >>> int(p[32].argmax()) in (30, 31, 32)
    True
    """
    model = model or load_model()
    if hasattr(model, "probability_of"):  # a convolutional detector reads the image itself
        return model.probability_of(flat)
    return model.probability(pixel_features(flat))
