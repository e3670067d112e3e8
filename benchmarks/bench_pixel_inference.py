"""The learned detector's pixel model at run time: features and classifier, time per 4 MP map.

    python benchmarks/bench_pixel_inference.py [--repeat 3]

One "moderate" synthetic face of 1633 x 2449 px (4 MP, the working grid a 12-24 MP photo is
processed on) is flattened as extraction does (:func:`rockmass.imaging.learned.model_input`); then,
each the best of ``--repeat`` runs in this process:

- ``features``: :func:`rockmass.imaging.features.pixel_features` (27 maps);
- ``classifier, block B``: the shipped model's forward pass (eq. (3.2), the standardisation's
  division folded into the first layer; a numba kernel since session 26) over the 4 M columns in
  blocks of B, the default 512 and 8192, and the largest difference of its probabilities
  from the default's (the block size must not change the answer);
- ``NumPy, block B``: the same forward pass with NumPy's matrix product (its BLAS library's
  threads), as it was from session 15 to 25 (blocks of 8192), written out here;
- ``unfolded, block 262 144``: the forward pass as it was before session 15 (standardise, clip,
  then the layers, in blocks of 262 144), written out here, with its largest difference from
  the default;
- ``... , ridge chain beside it``: the kernel and the NumPy forward pass while a second thread
  runs the ridge detector's whole chain on the same face, as ``detector = "auto"`` does: wall
  time of the forward pass, and the process's CPU time over the pair (the ridge chain's own
  and what the forward pass's threads take from it).

Times are the best of ``--repeat`` runs; ``cpu_s`` is the process's CPU time in that run.

Also the model file's size. Rows go to benchmarks/results/bench_pixel_inference.json.
"""

from __future__ import annotations

import argparse
import threading
import time

import numpy as np

from _common import header, save, table

SHAPE_PX = (1633, 2449)
#: Block sizes timed per forward pass: the kernel's default and NumPy's two.
BLOCKS = {"classifier": (512, 8192), "NumPy": (8192, 262144)}


def best_of(fn, repeat: int) -> dict:
    """Wall time of the fastest of ``repeat`` calls and the process's CPU time in it."""
    runs = []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        runs.append((time.perf_counter() - t0, time.process_time() - c0))
    wall, cpu = min(runs)
    return {"time_s": wall, "cpu_s": cpu}


def numpy_predict(stage, columns, block: int = 8192) -> np.ndarray:
    """Eq. (3.2) as :meth:`~rockmass.imaging.learned.Stage.predict` computed it from session 15 to
    25: the folded layers with NumPy's matrix product, in blocks of ``block`` columns."""
    low, high, mean, weights, biases = stage._folded
    out = np.empty(columns.shape[1], dtype=np.float32)
    for start in range(0, columns.shape[1], block):
        z = np.clip(columns[:, start:start + block], low, high)
        z -= mean
        for k, (w, b) in enumerate(zip(weights, biases)):
            z = w @ z
            z += b
            if k < len(weights) - 1:
                np.maximum(z, 0.0, out=z)
        out[start:start + block] = 1.0 / (1.0 + np.exp(-np.clip(z[0], -30, 30)))
    return out


def unfolded_predict(stage, columns, block: int = 262144) -> np.ndarray:
    """Eq. (3.2) as :meth:`~rockmass.imaging.learned.Stage.predict` computed it before session 15:
    z = clip((x - m) / s, ±6), then each layer as Wᵀz + b, ReLU between, logistic at the end."""
    from rockmass.imaging.learned import CLIP_SD

    mean, std = stage.mean[:, None], stage.std[:, None]
    out = np.empty(columns.shape[1], dtype=np.float32)
    for start in range(0, columns.shape[1], block):
        z = np.clip((columns[:, start:start + block] - mean) / std, -CLIP_SD, CLIP_SD)
        for k, (w, b) in enumerate(zip(stage.weights, stage.biases)):
            z = w.T @ z + b[:, None]
            if k < len(stage.weights) - 1:
                np.maximum(z, 0.0, out=z)
        out[start:start + block] = 1.0 / (1.0 + np.exp(-np.clip(z[0], -30, 30)))
    return out


def main(argv=None) -> int:
    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.features import pixel_features
    from rockmass.imaging.learned import MODEL_FILE, load_model, model_input
    from rockmass.imaging.synthetic import synthetic_face

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    print(header("the learned detector's pixel model: features and classifier on a 4 MP map"))
    face = synthetic_face("moderate", seed=1, shape_px=SHAPE_PX, m_per_px=0.005)
    flat = model_input(face.image.astype(np.float32) / 255.0)
    stage = load_model().stages[0]
    features = pixel_features(flat)
    columns = features.reshape(features.shape[0], -1)
    reference = stage.predict(columns)
    rows = [{"step": "features", **best_of(lambda: pixel_features(flat), args.repeat)}]
    forward = {"classifier": lambda block: stage.predict(columns, block=block),
               "NumPy": lambda block: numpy_predict(stage, columns, block)}
    for name, predict in forward.items():
        for block in BLOCKS[name]:
            rows.append({"step": f"{name}, block {block}",
                         **best_of(lambda: predict(block), args.repeat),
                         "max_diff": float(np.abs(predict(block) - reference).max())})
    rows.append({"step": "unfolded, block 262144",
                 **best_of(lambda: unfolded_predict(stage, columns), args.repeat),
                 "max_diff": float(np.abs(unfolded_predict(stage, columns) - reference).max())})
    for name, predict in forward.items():
        for block in BLOCKS[name]:
            runs = []
            for _ in range(args.repeat):
                side = threading.Thread(target=extract, args=(face.image,),
                                        kwargs=dict(m_per_px=face.m_per_px,
                                                    params=ExtractParams(detector="ridge")))
                c0 = time.process_time()
                side.start()
                t0 = time.perf_counter()
                predict(block)
                wall = time.perf_counter() - t0
                side.join()
                runs.append((wall, time.process_time() - c0))
            wall, cpu = min(runs)
            rows.append({"step": f"{name}, block {block}, ridge chain beside it",
                         "time_s": wall, "cpu_s": cpu})
    for row in rows:
        row["MP_per_s"] = columns.shape[1] / 1e6 / row["time_s"]
    print(f"\nmodel {MODEL_FILE.name}: {MODEL_FILE.stat().st_size} bytes; map {SHAPE_PX[0]} x "
          f"{SHAPE_PX[1]} px ({columns.shape[1] / 1e6:.1f} MP), best of {args.repeat}")
    print(table(rows, [("step", "s"), ("time_s", ".3f"), ("cpu_s", ".3f"), ("MP_per_s", ".1f"),
                       ("max_diff", ".1e")]))
    path = save("bench_pixel_inference", {"model_bytes": MODEL_FILE.stat().st_size,
                                          "shape_px": SHAPE_PX, "rows": rows})
    print(f"\nrows saved to {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
