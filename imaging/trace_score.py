"""How likely each extracted trace is a joint: a per-trace logistic model trained on synthetic faces
(docs/imaging.md §7.1).

A detector's own response says little about whether a trace is a joint (on the real photographs of
docs/imaging.md §8.1 it orders true above false traces worse than the trace's contrast or length;
§7.1 gives the figures). The joint score combines four properties of a trace that do not depend on
the camera, each measured on the trace the user gets:

- ``log(L / w)``: its length in joint widths (long traces are joints, texture is short);
- ``contrast``: how much darker than the face it is, 1 - mean / median of the flattened image
  (:func:`rockmass.imaging.vectorize.trace_contrast`);
- ``log(b / w)``: the width b of the detector's mask band along it, in joint widths (a joint's
  band is at least as wide as the joint, a texture ridge's is thinner);
- ``straightness``: its end-to-end distance over its length (a rubble rim or texture loop curls).

with w the expected joint width. The score is the logistic model

    s = σ(β₀ + Σ_k β_k (x_k - μ_k) / σ_k),   σ(t) = 1 / (1 + e^{-t})                    (7.1)

one per detector, with standardisation (μ, σ) and weights β fitted by
:mod:`rockmass.imaging.train_trace_score` on synthetic faces only, class-balanced and weighted by
trace length. The weights ship in the package (:data:`MODEL_FILE`, a few hundred bytes, read
without pickle).
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import numpy as np

__all__ = ["MODEL_FILE", "FEATURE_NAMES", "LOW_SCORE", "trace_features", "joint_score", "load",
           "scoring", "unscored"]

#: The shipped weights, inside the installed package.
MODEL_FILE = Path(__file__).resolve().parent / "models" / "trace_score.npz"
FEATURE_NAMES = ("log_length_widths", "contrast", "log_band_widths", "straightness")
#: Traces scoring below this are "low confidence": the summary's statistics are given without them too.
LOW_SCORE = 0.5

_CACHE: dict[str, dict] = {}
_UNSCORED = [0]  # depth of nested unscored() blocks


def scoring() -> bool:
    """Whether :func:`rockmass.imaging.extract` scores its traces (False only inside :func:`unscored`)."""
    return _UNSCORED[0] == 0


@contextmanager
def unscored():
    """Context in which :func:`rockmass.imaging.extract` leaves out the ``joint_score`` attribute:
    for fitting the score's weights, before any exist (:mod:`rockmass.imaging.train_trace_score`)."""
    _UNSCORED[0] += 1
    try:
        yield
    finally:
        _UNSCORED[0] -= 1


def trace_features(trace_map, *, m_per_px: float, joint_width_px: float) -> np.ndarray:
    """The (n, 4) features of :data:`FEATURE_NAMES` of a trace map that carries ``contrast`` and
    ``band_width_px`` attributes (as :func:`rockmass.imaging.extract` gives them).

    ``m_per_px`` is the scale of the photograph the traces were drawn on (metres, or 1 for traces in
    pixels) and ``joint_width_px`` the expected joint width on it.

    Examples
    --------
    >>> from rockmass.dfn import TraceMap
    >>> t = TraceMap.from_polylines([[(0, 0), (30, 0)], [(0, 10), (3, 14), (6, 10)]],
    ...                             attributes={"contrast": [0.4, 0.1], "band_width_px": [3.0, 1.5]})
    >>> trace_features(t, m_per_px=1.0, joint_width_px=3.0).round(3).tolist()
    [[2.303, 0.4, 0.0, 1.0], [1.204, 0.1, -0.693, 0.6]]
    """
    n = trace_map.n_traces
    if n == 0:
        return np.zeros((0, len(FEATURE_NAMES)))
    width = float(joint_width_px)
    lengths_px = np.asarray(trace_map.lengths_m(), dtype=float) / float(m_per_px)
    ends = np.array([trace_map.polyline(i)[[0, -1]] for i in range(n)])  # (n, 2 ends, 2)
    chords = np.hypot(*(ends[:, 1] - ends[:, 0]).T) / float(m_per_px)
    band = np.asarray(trace_map.attributes["band_width_px"], dtype=float)
    return np.column_stack([np.log(np.maximum(lengths_px, 1e-9) / width),
                            np.asarray(trace_map.attributes["contrast"], dtype=float),
                            np.log(np.maximum(band, 0.25) / width),
                            np.clip(chords / np.maximum(lengths_px, 1e-9), 0.0, 1.0)])


def load(path=None) -> dict:
    """The per-detector weights ``{detector: (mean, std, beta)}`` of a model file (default the
    shipped one); cached per path."""
    key = str(Path(path or MODEL_FILE).resolve())
    if key not in _CACHE:
        if not Path(key).is_file():
            raise FileNotFoundError(f"{key}: the trace score's model file is missing (it ships with "
                                    "rockmass; reinstall, or train one with python -m "
                                    "rockmass.imaging.train_trace_score)")
        with np.load(key, allow_pickle=False) as data:
            detectors = sorted({name.split("_")[0] for name in data.files if name.endswith("_beta")})
            _CACHE[key] = {d: (data[f"{d}_mean"], data[f"{d}_std"], data[f"{d}_beta"])
                           for d in detectors}
    return _CACHE[key]


def joint_score(features: np.ndarray, detector: str, *, path=None) -> np.ndarray:
    """Eq. (7.1) for each row of ``features`` (n, 4), with the weights fitted for ``detector``."""
    weights = load(path)
    if detector not in weights:
        raise ValueError(f"the trace score has no weights for detector {detector!r} "
                         f"(has {sorted(weights)})")
    mean, std, beta = weights[detector]
    x = np.asarray(features, dtype=float).reshape(-1, len(FEATURE_NAMES))
    t = beta[0] + ((x - mean) / std) @ beta[1:]
    return 1.0 / (1.0 + np.exp(-np.clip(t, -30.0, 30.0)))
