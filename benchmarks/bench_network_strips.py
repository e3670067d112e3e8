"""The convolutional network over a large grid: one pass or strips of rows (docs/imaging.md §3.6).

    python benchmarks/bench_network_strips.py [--sizes 1,2,4,8] [--passes inf,1.5,0.5] [--repeat 3]

:meth:`rockmass.imaging.joint_net.ConvModel.probability_of` sends a grid of more than
``MAX_PASS_PIXELS`` (1.5 MP) through the network in strips of rows, each with ``HALO_PX`` rows of
context above and below, so that the map is the one pass's. Why strips, and at what size? Each run
is a fresh process (the memory a pass leaves allocated would hide the next one's): it renders a
synthetic "moderate" face of the size asked for (seed 1; its grey levels flattened as the chain
does, :func:`rockmass.imaging.learned.model_input`), reads the shipped network, resets the
process's peak memory (``/proc/self/clear_refs``) and runs the map twice, at the given largest
pass (``inf``: one pass). Per run: the first pass's wall time (OpenCV plans the network for the
input's shape), the second's, the CPU time of both (user + system, all threads), the rise of the
peak resident memory over the memory before the first pass (``VmHWM`` - ``VmRSS`` of
``/proc/self/status``), and the largest difference of the map from the one pass's at that size.
Medians over ``--repeat`` fresh processes. Rows also go to
benchmarks/results/bench_network_strips.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

COLUMNS = [("MP", "g"), ("largest_pass_MP", "s"), ("passes", "d"), ("first_s", ".2f"),
           ("second_s", ".2f"), ("cpu_s", ".2f"), ("peak_rise_GB", ".2f"),
           ("max_diff", ".1e"), ("runs", "d")]
ASPECT = 1.5  # width over height of the faces, as a 3:2 camera frame


def _memory_kb(field: str) -> int:
    """``VmRSS`` or ``VmHWM`` of this process, kB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise RuntimeError(f"/proc/self/status has no {field}")


def child(megapixels: float, max_pass_pixels: float, out: str) -> None:
    """One run (module notes), in this process; its figures as JSON on stdout."""
    import gc
    import time

    from rockmass.imaging import synthetic_face
    from rockmass.imaging.joint_net import (CNN_MODEL_FILE, padded_shape, read_conv_model,
                                            strip_rows)
    from rockmass.imaging.learned import model_input

    height = int(round(np.sqrt(megapixels * 1e6 / ASPECT)))
    face = synthetic_face("moderate", seed=1, shape_px=(height, int(round(height * ASPECT))))
    grey = face.image if face.image.ndim == 2 else face.image.mean(axis=2)
    flat = model_input(np.asarray(grey, dtype=np.float32))
    del face, grey
    model = read_conv_model(CNN_MODEL_FILE)
    gc.collect()
    Path("/proc/self/clear_refs").write_text("5")  # peak memory from here on
    before_kb = _memory_kb("VmRSS")
    cpu0, times = os.times(), []
    for _ in range(2):
        t0 = time.perf_counter()
        probability = model.probability_of(flat, max_pass_pixels=max_pass_pixels)
        times.append(time.perf_counter() - t0)
    cpu1 = os.times()
    peak_kb = _memory_kb("VmHWM")
    np.save(out, probability)
    padded = padded_shape(probability.shape)
    passes = -(-padded[0] // strip_rows(padded, max_pass_pixels)[1])
    print(json.dumps({"first_s": times[0], "second_s": times[1], "passes": passes,
                      "cpu_s": (cpu1.user - cpu0.user) + (cpu1.system - cpu0.system),
                      "peak_rise_GB": (peak_kb - before_kb) / 1024 ** 2}))


def run(megapixels: float, max_pass_pixels: float, out: Path) -> dict:
    """One fresh process's figures (:func:`child`)."""
    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).resolve().parent)!r}); "
            f"import bench_network_strips as b; "
            f"b.child({megapixels!r}, float({str(max_pass_pixels)!r}), {str(out)!r})")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1,2,4,8", help="grid sizes, MP (default 1,2,4,8)")
    parser.add_argument("--passes", default="inf,1.5,0.5",
                        help="largest pass, MP; inf: one pass (default inf,1.5,0.5)")
    parser.add_argument("--repeat", type=int, default=3, help="fresh processes per setting")
    args = parser.parse_args(argv)
    sizes = [float(s) for s in args.sizes.split(",") if s.strip()]
    passes = [s.strip() for s in args.passes.split(",") if s.strip()]
    if "inf" not in passes:
        passes.insert(0, "inf")  # the reference map
    print(header("the convolutional network over a large grid: one pass or strips"))
    print(f"load average {os.getloadavg()[0]:.2f} (2 shared cores); medians of {args.repeat} "
          "fresh processes")
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_network_strips_") as tmp:
        for size in sizes:
            reference = None
            for largest in passes:
                limit = float(largest) * 1e6
                runs, maps = [], []
                for k in range(args.repeat):
                    path = Path(tmp) / f"map_{size:g}_{largest}_{k}.npy"
                    runs.append(run(size, limit, path))
                    maps.append(np.load(path))
                if reference is None:
                    reference = maps[0]
                row = {"MP": size, "largest_pass_MP": "one pass" if largest == "inf" else largest,
                       "passes": runs[0]["passes"], "runs": len(runs),
                       "max_diff": float(max(np.abs(m - reference).max() for m in maps))}
                for key in ("first_s", "second_s", "cpu_s", "peak_rise_GB"):
                    row[key] = statistics.median(r[key] for r in runs)
                rows.append(row)
                print(table(rows[-1:], COLUMNS).splitlines()[-1], flush=True)
    print("\n" + table(rows, COLUMNS))
    print(f"\nrows: {save('bench_network_strips', {'rows': rows})}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
