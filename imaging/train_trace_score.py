"""Fit the per-trace joint score (eq. (7.1), :mod:`rockmass.imaging.trace_score`) on synthetic faces.

    OMP_NUM_THREADS=1 python -m rockmass.imaging.train_trace_score [--out FILE] [--faces N]
                                                                   [--plain-faces N] [--seed S]

For each detector, traces are extracted with the trace filters off (no contrast or band-width
filter, a 20 px length floor) from ``--faces`` (default 24) field-like faces in the tunnel style
(:func:`rockmass.imaging.synthetic_field.field_face`, ``TUNNEL_STYLE``: shadowed and stepped joints,
minor cracks, crevice loops, rubble, plates, half-casts, shotcrete), 800 x 1200 px at 8 mm/px,
seeds from ``--seed`` (default 20 000, apart from the seeds of the tests and benchmarks, 0-999, and
of the pixel model, 10 000+). A trace is a joint when at least half of its drawn pixels lie within
3 px of a true centre line. The field faces label what the real photographs' labels mark, the
major joints, and leave out minor cracks, loops and rims; ``--plain-faces N`` adds plain faces
(:func:`rockmass.imaging.synthetic.synthetic_face`, "moderate" and "hard"), whose truth is every
line drawn, however faint (default none: with half as many as field faces, the score ordered the
traces of the real ``train/`` photographs worse than their contrast alone, docs/imaging.md §7.1).
The logistic model is fitted by Newton's method on the class-balanced log loss, each trace weighted
by its length (so the score ranks trace *length*, as P21 counts it), with a small ridge penalty
(1e-3) for a unique optimum. No real photograph is used.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time

import numpy as np

from ..dfn.atomic import atomic_open
from .trace_score import FEATURE_NAMES, MODEL_FILE, trace_features, unscored

__all__ = ["trace_labels", "fit_logistic", "main"]

#: A trace is true when this share of its pixels lies within TOLERANCE_PX of the truth.
TRUE_SHARE = 0.5
TOLERANCE_PX = 3.0


def trace_labels(traces, truth_lines, m_per_px: float, *, tolerance_px: float = TOLERANCE_PX):
    """(labels, drawn pixels) of each trace: label 1 when at least :data:`TRUE_SHARE` of its 1-px
    drawing on the grid of the bool mask ``truth_lines`` (the true centre lines, 1 px wide) lies
    within ``tolerance_px`` of them, else 0; a trace that draws no pixel is 0 with 0 pixels."""
    import cv2

    from .metrics import render_traces

    near = cv2.distanceTransform(np.where(truth_lines, 0, 255).astype(np.uint8), cv2.DIST_L2,
                                 cv2.DIST_MASK_PRECISE) <= tolerance_px
    labels, pixels = np.zeros(traces.n_traces), np.zeros(traces.n_traces, dtype=np.int64)
    for i in range(traces.n_traces):
        drawn = render_traces(traces.subset([i]), near.shape, m_per_px)
        pixels[i] = drawn.sum()
        labels[i] = float(pixels[i] > 0 and near[drawn].mean() >= TRUE_SHARE)
    return labels, pixels


def fit_logistic(x, y, weight, *, penalty: float = 1e-3, iterations: int = 50):
    """(mean, std, beta) of eq. (7.1) minimising the weighted, class-balanced log loss.

    Each class gets half the total weight; Newton steps on the standardised features with an
    intercept, ridge ``penalty`` on every coefficient.
    """
    x, y, weight = (np.asarray(a, dtype=float) for a in (x, y, weight))
    if not (0 < y.mean() < 1):
        raise ValueError("the training traces must include joints and non-joints")
    mean, std = x.mean(axis=0), np.maximum(x.std(axis=0), 1e-9)
    z = np.column_stack([np.ones(len(x)), (x - mean) / std])
    c = weight * np.where(y > 0.5, 0.5 / (weight * y).sum(), 0.5 / (weight * (1 - y)).sum())
    beta = np.zeros(z.shape[1])
    for _ in range(iterations):
        p = 1.0 / (1.0 + np.exp(-np.clip(z @ beta, -30, 30)))
        gradient = z.T @ (c * (p - y)) + penalty * beta
        hessian = (z * (c * p * (1 - p))[:, None]).T @ z + penalty * np.eye(len(beta))
        step = np.linalg.solve(hessian, gradient)
        beta -= step
        if np.abs(step).max() < 1e-10:
            break
    return mean, std, beta


def _faces(first_seed: int, n_field: int, n_plain: int):
    from .synthetic import synthetic_face
    from .synthetic_field import TUNNEL_STYLE, field_face

    for i in range(n_field + n_plain):
        seed = first_seed + i
        if i < n_field:
            yield field_face(seed=seed, shape_px=(800, 1200), m_per_px=0.008, style=TUNNEL_STYLE)
        else:
            yield synthetic_face(("moderate", "hard")[i % 2], seed=seed, shape_px=(800, 1200),
                                 m_per_px=0.008)


def training_traces(detector: str, first_seed: int, n_field: int, n_plain: int):
    """(features, labels, lengths in px) of the unfiltered traces of the training faces."""
    from .extract import NO_TRACE_FILTERS, ExtractParams, extract
    from .metrics import render_traces

    params = ExtractParams(detector=detector, **NO_TRACE_FILTERS)
    xs, ys, ws = [], [], []
    for face in _faces(first_seed, n_field, n_plain):
        with unscored():
            result = extract(face.image, m_per_px=face.m_per_px, params=params)
        traces = result.traces
        xs.append(trace_features(traces, m_per_px=face.m_per_px,
                                 joint_width_px=result.joint_width_px))
        truth = render_traces(face.truth, face.image.shape, face.m_per_px)
        ys.append(trace_labels(traces, truth, face.m_per_px)[0])
        ws.append(traces.lengths_m() / face.m_per_px)
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(ws)


def main(argv=None) -> int:
    import cv2

    from .extract import DETECTORS

    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(MODEL_FILE), help=f"model file (default {MODEL_FILE})")
    parser.add_argument("--faces", type=int, default=24, help="field-like faces (default 24)")
    parser.add_argument("--seed", type=int, default=20_000, help="first face seed (default 20000)")
    parser.add_argument("--plain-faces", type=int, default=0, dest="plain_faces",
                        help="plain synthetic faces (default 0)")
    args = parser.parse_args(argv)
    if args.faces < 1:
        parser.error("--faces must be at least 1")
    if args.plain_faces < 0:
        parser.error("--plain-faces must not be negative")
    n_plain = args.plain_faces
    t0 = time.perf_counter()
    arrays, info = {}, {"command": "python -m rockmass.imaging.train_trace_score " +
                        " ".join(argv if argv is not None else sys.argv[1:]),
                        "seed": args.seed, "field_faces": args.faces, "plain_faces": n_plain,
                        "features": list(FEATURE_NAMES), "detectors": {}}
    for detector in DETECTORS:
        x, y, w = training_traces(detector, args.seed, args.faces, n_plain)
        mean, std, beta = fit_logistic(x, y, w)
        arrays.update({f"{detector}_mean": mean, f"{detector}_std": std, f"{detector}_beta": beta})
        info["detectors"][detector] = {"traces": int(len(y)), "joint_share": round(float(y.mean()), 3),
                                       "beta": [round(float(b), 4) for b in beta]}
    info.update(total_s=round(time.perf_counter() - t0, 1), python=platform.python_version(),
                numpy=np.__version__, data="synthetic faces only (field_face TUNNEL_STYLE, synthetic_face)")
    with atomic_open(args.out, "wb") as handle:  # a killed run keeps the file there was
        np.savez(handle, info=np.array(json.dumps(info, sort_keys=True)), **arrays)
    print(json.dumps(info, indent=2))
    print(f"wrote {args.out} in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
