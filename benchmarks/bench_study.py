"""Study executors: overhead per case and the speed-up of 2 local workers over 1.

The cases are those of samples/study_cavern.toml restricted to the middle spacing (7 and 9 m,
about 200 blocks, 5-15 s a case): theta 40 / 60 / 90 deg x 2 realizations. With cases of a second
or two the pool's start-up (spawning, imports, loading the cached kernels: a few seconds per
worker) is not paid back.

- overhead per case = (study run time - sum of the cases' own wall times) / cases, serially, as a
  fraction of the mean case time (target <= 5 %): validation, task dispatch, case.json and
  results.csv writes, report and manifest;
- speed-up = run time with 1 worker / run time with 2 workers on the same cases (target >= 1.7 on
  an otherwise idle 2-core machine; the load average is recorded beside it).

    python benchmarks/bench_study.py
"""

from __future__ import annotations

import json
import os
import re
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "study_cavern.toml"


def _config(tmp: Path) -> Path:
    text = SAMPLE.read_text(encoding="utf-8")
    text = re.sub(r"blocks\.two_sets\.spacing_m = \[\[.*\]\]", "blocks.two_sets.spacing_m = "
                  "[[7.0, 9.0]]", text)
    path = tmp / "study.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _run(cfg: Path, out: Path, workers: int) -> dict:
    from rockmass.cli import main

    t0 = time.perf_counter()
    code = main(["study", str(cfg), "--out", str(out), "--workers", str(workers)])
    wall = time.perf_counter() - t0
    if code != 0:
        raise SystemExit(f"study failed with exit code {code}")
    manifest = json.loads((out / "manifest.json").read_text())
    t = manifest["timings_s"]
    n = manifest["extra"]["cases"]
    return {"workers": workers, "cases": n, "command_s": wall, "run_s": t["run_s"],
            "case_sum_s": t["case_wall_time_sum_s"], "mean_case_s": t["case_wall_time_sum_s"] / n,
            "overhead_per_case_s": (t["run_s"] - t["case_wall_time_sum_s"]) / n
            if workers == 1 else None}


def main() -> None:
    print(header("rockmass study: executor overhead and local speed-up"))
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        cfg = _config(tmp)
        _run(cfg, tmp / "warm", 1)  # numba's cache and imports warm, as in a second study
        serial = _run(cfg, tmp / "serial", 1)
        pool = _run(cfg, tmp / "pool", 2)
    load1 = os.getloadavg()[0]
    serial["overhead_fraction"] = serial["overhead_per_case_s"] / serial["mean_case_s"]
    pool["speedup"] = serial["run_s"] / pool["run_s"]
    rows = [serial, pool]
    print(table(rows, [("workers", "d"), ("cases", "d"), ("run_s", ".2f"), ("case_sum_s", ".2f"),
                       ("mean_case_s", ".2f"), ("overhead_per_case_s", ".3f"),
                       ("overhead_fraction", ".1%"), ("speedup", ".2f")]))
    print(f"load average (1 min) before / after: {load0:.2f} / {load1:.2f} on {os.cpu_count()} "
          "cores; targets: overhead <= 5 % of a case, speed-up >= 1.7 on an idle 2-core machine")
    path = save("bench_study", {"rows": rows, "load_average_before": load0,
                                "load_average_after": load1, "cpu_count": os.cpu_count()})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
