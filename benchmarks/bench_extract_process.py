"""Whole-process extraction: ``rockmass extract PHOTO --out DIR``, one face at 3-24 MP (issue 20).

    python benchmarks/bench_extract_process.py [--quick] [--sizes 3,6,12,16,24]
                                               [--detectors ridge,learned,auto,auto-cnn,fine]
                                               [--no-full-resolution]

One synthetic face, 12 m x 8 m, with exact ground truth (:func:`rockmass.imaging.synthetic_face`,
"moderate" spoiling, seed 1), is photographed at several resolutions: it is rendered once at the
largest size asked for, with joints 5-30 mm wide *in metres* (2-15 px at 24 MP), and area-averaged
down to each smaller size, as a camera with fewer pixels would see the same face; every photo is an
RGB JPEG at quality 92 (a slight tint, so the command decodes and converts colour as for a real
photo). The traces in metres are the same at every size. (The generator by itself draws joints
1-6 px wide at any size, i.e. thinner in metres the finer the pixel, which is why this script
renders once and down-samples.)

Each run is the real command in a fresh process, ``rockmass extract PHOTO --out DIR --m-per-px S``
(decode, grey, down-sampling to 4 MP, the chain, statistics, box counting, overlay, rose, manifest),
with, per detector:

- ``default``: no width given: 3 pixels of the working grid (docs/imaging.md §1), what a user gets
  without thinking about it;
- ``width 15 mm``: ``--joint-width-m 0.0147`` (3 px of the 4 MP working grid of this face);
- ``width 3 input px``: ``--joint-width 3``, the default before issue 20 (1.2 working px at
  24 MP), kept to show the drift it had;
- ``pixel model kept`` (``auto`` and ``auto-cnn``): ``[imaging.params] auto_agreement = 1``, so
  that "auto" keeps the pixel model's traces over the ridge filter's, as on a textured face, and
  runs the network (docs/imaging.md §3.6: only then; ``auto-cnn`` is "auto" without the network,
  ``auto_network_ratio = inf``). On this clean face "auto" keeps the ridge filter's traces, and
  the network is not run: these rows give its cost where it is;
- ``full res``: ``[imaging.params] max_megapixels = 1000`` at 12 MP (ridge only; not with
  ``--quick`` or ``--no-full-resolution``), where the pixel settings are multiplied by
  sqrt(12 / 4) (areas by its square; ``ExtractParams.on_grid``) and the default width follows.

Per run: wall and CPU time of the child (``os.wait4`` rusage, user + system), MP/s = input pixels /
wall, the child's peak RSS (``ru_maxrss`` of that child alone, forked from a small launcher
process), the command's own step times (manifest.json: ``read_s`` decoding, ``chain_s`` the chain
of :func:`extract` from summary.json, ``analyse_s`` statistics and box counting; the rest of the
wall time is start-up, imports and writing the overlay, rose and files) and, from
``traces.geojson`` against the truth: dP21, dP20 (both over the truth's window) and buffered F1 at
a 15 mm tolerance (3 px of a 5 mm scoring grid, the same grid at every size). A first run on the
smallest photo per detector is reported apart (imports, numba cache load; not with ``--quick``).
Python's bytecode cache is on for the children, as it is for a package installed by pip, which
compiles the modules at install: this machine sets ``PYTHONDONTWRITEBYTECODE``, under which an
editable install compiles rockmass's modules in every run; without it they are
compiled once, into ``__pycache__`` beside the sources. With ``--quick`` one untimed run goes
first, for the numba and bytecode caches.
Targets (issue 20): >= 2 MP/s whole process at 12-24 MP on 2 cores, <= 2 GB, and dP21 / dP20 that
do not drift with resolution. Rows also go to benchmarks/results/bench_extract_process.json
(``..._quick.json`` with ``--quick``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _common import header, save, table

FACE_WIDTH_M, FACE_HEIGHT_M = 12.0, 8.0
SEED = 1
#: Joint widths of the face, metres (drawn uniformly per trace, in whole pixels of the render).
JOINT_WIDTH_RANGE_M = (0.005, 0.030)
#: Joint width given with ``width 15 mm``: 3 px of this face's 4 MP working grid (12 m / 2449 px).
JOINT_WIDTH_M = 0.0147
#: Scoring grid and buffer: 3 px of 5 mm = a 15 mm tolerance at every size.
SCORE_M_PER_PX, SCORE_BUFFER_PX = 0.005, 3.0
JPEG_QUALITY = 92

COLUMNS = [("detector", "s"), ("setting", "s"), ("MP", ".1f"), ("work_MP", ".1f"), ("wall_s", ".2f"),
           ("cpu_s", ".2f"), ("read_s", ".2f"), ("chain_s", ".2f"), ("analyse_s", ".2f"),
           ("MP_per_s", ".2f"), ("peak_MB", ".0f"), ("n_traces", "d"), ("F1_15mm", ".3f"),
           ("dP21_%", "+.1f"), ("dP20_%", "+.1f")]


def shape_for(megapixels: float) -> tuple[int, int]:
    """(rows, cols) of a 3:2 photo of about ``megapixels``."""
    w = int(round(np.sqrt(megapixels * 1e6 * 1.5)))
    return int(round(w / 1.5)), w


def render(sizes_mp, folder: Path) -> tuple[dict, object]:
    """Render the face at the largest size, down-sample to each size, write the JPEGs and the truth.

    Returns ({megapixels: (path, m_per_px, shape)}, truth TraceMap)."""
    import cv2

    from rockmass.dfn import write_traces
    from rockmass.imaging.synthetic import DIFFICULTIES, synthetic_face

    h, w = shape_for(max(sizes_mp))
    m_per_px = FACE_WIDTH_M / w
    widths = tuple(max(int(round(v / m_per_px)), 1) for v in JOINT_WIDTH_RANGE_M)
    style = replace(DIFFICULTIES["moderate"], width_px=widths, jpeg_quality=100)
    face = synthetic_face("moderate", seed=SEED, shape_px=(h, w), m_per_px=m_per_px, style=style)
    write_traces(face.truth, folder / "truth.geojson")
    grey = face.image.astype(np.float32)
    rgb = np.clip(np.stack([grey * 0.9, grey, grey * 1.05], axis=2), 0, 255).astype(np.uint8)  # BGR
    photos = {}
    for size in sizes_mp:
        rows, cols = shape_for(size)
        img = (rgb if (rows, cols) == (h, w)
               else cv2.resize(rgb, (cols, rows), interpolation=cv2.INTER_AREA))
        path = folder / f"face_{size:g}MP.jpg"
        if not cv2.imwrite(str(path), img, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY]):
            raise OSError(f"{path}: could not write the photo")
        photos[size] = (path, FACE_WIDTH_M / cols, (rows, cols))
    return photos, face.truth


#: Runs the command from a small process of its own (fork + exec + wait4), so that the child's
#: ru_maxrss is its own: an exec'd child inherits the peak RSS of the memory image it replaces
#: (this script's, which rendered the 24 MP face), and a forked one starts at its parent's RSS.
_LAUNCHER = """
import json, os, sys, time
report, cmd = sys.argv[1], sys.argv[2:]
t0 = time.perf_counter()
pid = os.fork()
if pid == 0:
    os.execv(cmd[0], cmd)
_, status, usage = os.wait4(pid, 0)
wall = time.perf_counter() - t0
with open(report, "w") as f:
    json.dump({"code": os.waitstatus_to_exitcode(status), "wall_s": wall,
               "cpu_s": usage.ru_utime + usage.ru_stime, "peak_MB": usage.ru_maxrss / 1024}, f)
"""


def run_command(photo: Path, out: Path, m_per_px: float, extra: list[str]) -> dict:
    """``rockmass extract`` in a fresh process; wall, CPU and peak RSS of that child alone."""
    import subprocess

    exe = shutil.which("rockmass", path=str(Path(sys.executable).parent)) or shutil.which("rockmass")
    cmd = [exe, "extract", str(photo), "--out", str(out), "--m-per-px", repr(m_per_px), *extra]
    env = {**os.environ, "ROCKMASS_QUIET": "1"}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # compiled modules, as an installed package has them
    if out.exists():
        shutil.rmtree(out)
    report, log = out.parent / "child.json", out.parent / "child.log"
    with open(log, "w") as stream:
        subprocess.run([sys.executable, "-S", "-c", _LAUNCHER, str(report), *cmd], env=env,
                       stdout=stream, stderr=subprocess.STDOUT, check=True)
    res = json.loads(report.read_text())
    if res.pop("code") != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{log.read_text()}")
    return {**res, "command": " ".join(cmd[1:])}


def score(out: Path, truth) -> dict:
    """Accuracy of the traces the command wrote, against the truth (metres, the truth's window)."""
    from rockmass.dfn import read_traces
    from rockmass.imaging.metrics import trace_accuracy

    summary = json.loads((out / "summary.json").read_text())
    extracted = read_traces(out / "traces.geojson", frame="face")
    acc = trace_accuracy(extracted, truth, m_per_px=SCORE_M_PER_PX, buffer_px=SCORE_BUFFER_PX)
    ext = summary["extraction"]
    work = ext["scale"]["work_shape_px"]
    steps = json.loads((out / "manifest.json").read_text()).get("timings_s", {})
    return {"n_traces": int(extracted.n_traces), "F1_15mm": acc.f1, "precision": acc.precision,
            "recall": acc.recall, "dP21_%": 100 * acc.p21_rel_error, "dP20_%": 100 * acc.p20_rel_error,
            "work_MP": work[0] * work[1] / 1e6, "chain_s": float(sum(ext["timings_s"].values())),
            "read_s": steps.get("read_s"), "analyse_s": steps.get("analyse_s"),
            "timings_s": ext["timings_s"], "processing": ext["scale"]["processing"]}


def detector_args(detector: str, folder: Path, *, pixel_model_kept: bool = False) -> list[str]:
    """The command's arguments for a detector name; "auto-cnn" is "auto" without the
    convolutional network among its candidates, given by a config in ``folder`` (docs/imaging.md
    §3.6); ``pixel_model_kept`` ("auto" and "auto-cnn" only) adds ``auto_agreement = 1`` to the
    config, so that "auto" keeps the pixel model's traces over the ridge filter's (and runs the
    network), as on a textured face. "fine" is ``--joints all`` (every joint, docs/imaging.md
    §8.4)."""
    if detector == "fine":
        if pixel_model_kept:
            raise ValueError("fine: pixel_model_kept is a setting of auto and auto-cnn")
        return ["--joints", "all"]
    settings = (["auto_network_ratio = inf"] if detector == "auto-cnn" else []) \
        + (["auto_agreement = 1.0"] if pixel_model_kept else [])
    if not settings:
        return ["--detector", detector]
    if detector not in ("auto", "auto-cnn"):
        raise ValueError(f"{detector}: pixel_model_kept is a setting of auto and auto-cnn")
    config = folder / f"{detector.replace('-', '_')}{'_pixel_model' * pixel_model_kept}.toml"
    config.write_text("[imaging.params]\n" + "".join(f"{line}\n" for line in settings))
    return ["--detector", "auto", "--config", str(config)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the smallest two sizes (3 and 6 MP)")
    parser.add_argument("--sizes", default="3,6,12,16,24", help="photo sizes, MP (default 3,6,12,16,24)")
    parser.add_argument("--detectors", default="ridge,learned,auto",
                        help="--detector values (default all three), auto-cnn: auto with "
                             "[imaging.params] auto_network_ratio = inf, i.e. without the "
                             "convolutional network (docs/imaging.md §3.6), or fine: "
                             "--joints all (§8.4)")
    parser.add_argument("--no-full-resolution", action="store_true",
                        help="skip the max_megapixels = 1000 row at 12 MP")
    args = parser.parse_args(argv)
    sizes = sorted(float(s) for s in args.sizes.split(",") if s.strip())
    sizes = sizes[:2] if args.quick else sizes
    detectors = [d.strip() for d in args.detectors.split(",") if d.strip()]

    print(header("whole-process extraction: rockmass extract PHOTO --out DIR, one 12 m x 8 m face "
                 "at several resolutions"))
    print(f"load average {os.getloadavg()[0]:.2f} (2 shared cores); face: synthetic_face moderate, "
          f"seed {SEED}, joints {JOINT_WIDTH_RANGE_M[0] * 1e3:g}-{JOINT_WIDTH_RANGE_M[1] * 1e3:g} mm, "
          f"rendered at {max(sizes):g} MP and area-averaged down; RGB JPEG q{JPEG_QUALITY}")
    rows, first = [], []
    with tempfile.TemporaryDirectory(prefix="bench_extract_process_") as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        photos, truth = render(sizes, folder)
        print(f"rendered in {time.perf_counter() - t0:.1f} s; truth: {truth.n_traces} traces, "
              f"P21 {truth.total_length_m() / (FACE_WIDTH_M * FACE_HEIGHT_M):.3f} m/m2")
        out = folder / "out"
        path, m_per_px, _ = photos[sizes[0]]
        if args.quick:  # no first-run rows: one untimed run fills the caches
            run_command(path, out, m_per_px, detector_args(detectors[0], folder))
        for detector in detectors if not args.quick else ():  # first run per detector, apart
            res = run_command(path, out, m_per_px, detector_args(detector, folder))
            first.append({"detector": detector, "setting": "first run", "MP": sizes[0], **res,
                          **score(out, truth)})
        config = folder / "full_resolution.toml"
        config.write_text("[imaging.params]\nmax_megapixels = 1000\n")
        cases = []
        for size in sizes:
            for detector in detectors:
                cases.append((size, detector, "default", []))
                cases.append((size, detector, "width 15 mm", ["--joint-width-m", f"{JOINT_WIDTH_M}"]))
                cases.append((size, detector, "width 3 input px", ["--joint-width", "3"]))
                if detector in ("auto", "auto-cnn"):  # the network runs only then (§3.6)
                    cases.append((size, detector, "pixel model kept", None))
        if not args.quick and not args.no_full_resolution and 12.0 in sizes and "ridge" in detectors:
            cases.append((12.0, "ridge", "full res, default", ["--config", str(config)]))
            cases.append((12.0, "ridge", "full res, 15 mm",
                          ["--config", str(config), "--joint-width-m", f"{JOINT_WIDTH_M}"]))
        for size, detector, setting, extra in cases:
            path, m_per_px, shape = photos[size]
            try:
                command = (detector_args(detector, folder, pixel_model_kept=True)
                           if extra is None else [*detector_args(detector, folder), *extra])
                res = run_command(path, out, m_per_px, command)
            except RuntimeError as exc:  # keep the other rows; the failure is printed and saved
                print(f"  {detector} {setting} {size:g} MP failed: {exc}", flush=True)
                rows.append({"detector": detector, "setting": setting, "MP": size, "error": str(exc)})
                continue
            row = {"detector": detector, "setting": setting, "MP": shape[0] * shape[1] / 1e6,
                   "shape_px": list(shape), "m_per_px": m_per_px, **res, **score(out, truth)}
            row["MP_per_s"] = row["MP"] / row["wall_s"]
            rows.append(row)
            print(f"  {detector:8s} {setting:22s} {row['MP']:5.1f} MP  {row['wall_s']:6.2f} s",
                  flush=True)
    rows_ok = [r for r in rows if "error" not in r]
    for r in first:
        r["MP_per_s"] = r["MP"] / r["wall_s"]
    if first:
        print("\nfirst run per detector (smallest photo; the numba cache already filled)")
        print(table(first, COLUMNS))
    print("\nwhole process per size (fresh process per run; MP/s = input pixels / wall; peak = the "
          "child's ru_maxrss;\nF1 at 15 mm, dP21 / dP20 over the truth's window, from traces.geojson)")
    print(table(rows_ok, COLUMNS))
    name = "bench_extract_process_quick" if args.quick else "bench_extract_process"
    path = save(name, {"sizes_MP": sizes, "joint_width_range_m": JOINT_WIDTH_RANGE_M,
                       "joint_width_m": JOINT_WIDTH_M,
                       "score_tolerance_m": SCORE_M_PER_PX * SCORE_BUFFER_PX,
                       "first": first, "rows": rows})
    print(f"\nrows written to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
