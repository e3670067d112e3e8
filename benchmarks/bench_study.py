"""Study executors: overhead per case and the speed-up of 2 local workers over 1.

The cases are those of samples/study_cavern.toml at the two coarser spacings (7/9 m and 10/12 m):
theta 40 / 60 / 90 deg x 2 spacings x 2 realizations = 12 cases of 1-5 s (``--cases 6``: the 7/9 m
spacing alone, the set of the earlier measurements; ``--cases 18``: the whole sample, ~2 min).

- overhead per case = (study run time - sum of the cases' own wall times) / cases, serially, as a
  fraction of the mean case time (target <= 5 %): validation, task dispatch, case.json and
  results.csv writes;
- speed-up = wall time of ``rockmass study --workers 1`` / wall time of ``--workers 2`` on the same
  cases, each a fresh command (``python -m rockmass study``, what a user times: interpreter start,
  imports, numba's kernels loaded from its on-disk cache, the cases, the report); target >= 1.7 on
  a 2-core machine. ``run_speedup`` is the same ratio of the study's own run time (from the
  manifest: case dispatch to the last result, without interpreter start and config checks);
- ideal = what the cases allow on 2 workers with no start-up at all: the serial case times summed,
  divided by the makespan of those times dealt to 2 workers in the pool's order (longest estimated
  first); ``startup_s`` = when the workers' first cases started (spawn, imports, kernels warmed);
- each case's CPU time is recorded beside its wall time: case wall >> case CPU means the worker
  waited for a core (other processes on the machine), which no executor can fix. The load average
  before and after every run is in the table; the runs are repeated (``--repeat``) so that a quiet
  moment can be picked.

    python benchmarks/bench_study.py [--repeat 3] [--cases 6|12|18]
"""

from __future__ import annotations

import argparse
import heapq
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

SAMPLE = Path(__file__).resolve().parents[1] / "samples" / "study_cavern.toml"
SPACINGS = {6: "[[7.0, 9.0]]", 12: "[[7.0, 9.0], [10.0, 12.0]]",
            18: "[[5.0, 6.0], [7.0, 9.0], [10.0, 12.0]]"}  # 18: the whole sample


def _config(tmp: Path, n_cases: int) -> Path:
    text = SAMPLE.read_text(encoding="utf-8")
    text = re.sub(r"blocks\.two_sets\.spacing_m = \[\[.*\]\]",
                  f"blocks.two_sets.spacing_m = {SPACINGS[n_cases]}", text)
    path = tmp / f"study_{n_cases}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _makespan(times: list[float], workers: int) -> float:
    """List scheduling: each time, in order, goes to the worker that is free first."""
    free = [0.0] * workers
    for t in times:
        heapq.heappush(free, heapq.heappop(free) + t)
    return max(free)


def _run(cfg: Path, out: Path, workers: int) -> dict:
    """``python -m rockmass study`` as a fresh process; its wall time and what it wrote."""
    load0 = os.getloadavg()[0]
    c0 = os.times()
    epoch0 = time.time()
    t0 = time.perf_counter()
    env = {**os.environ, "ROCKMASS_QUIET": "1"}
    proc = subprocess.run([sys.executable, "-m", "rockmass", "study", str(cfg), "--out", str(out),
                           "--workers", str(workers)], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    c1 = os.times()
    if proc.returncode != 0:
        raise SystemExit(f"study failed with exit code {proc.returncode}:\n{proc.stderr}")
    manifest = json.loads((out / "manifest.json").read_text())
    recs = [json.loads(p.read_text()) for p in sorted((out / "cases").glob("*/case.json"))]
    t = manifest["timings_s"]
    n = manifest["extra"]["cases"]
    cpu = (c1.user + c1.system - c0.user - c0.system) + (c1.children_user + c1.children_system
                                                         - c0.children_user - c0.children_system)
    firsts = {}
    for r in recs:
        firsts[r["worker_pid"]] = min(firsts.get(r["worker_pid"], 1e30), r["started_at"])
    return {"workers": workers, "cases": n, "command_s": wall, "run_s": t["run_s"],
            "case_sum_s": sum(r["wall_time_s"] for r in recs),
            "case_cpu_s": sum(r["cpu_time_s"] for r in recs),
            "mean_case_s": t["case_wall_time_sum_s"] / n, "process_cpu_s": cpu,
            "startup_s": max(firsts.values()) - epoch0,
            "overhead_per_case_s": (t["run_s"] - t["case_wall_time_sum_s"]) / n
            if workers == 1 else None,
            "load_before": load0, "load_after": os.getloadavg()[0],
            "case_times": {r["case"]: r["wall_time_s"] for r in recs},
            "numba_threads": sorted({r.get("numba_threads") for r in recs}, key=str),
            "warmups": sorted({r.get("worker_warmups") for r in recs}, key=str)}


def _order(cfg: Path) -> list[int]:
    """Case indices in the order the pool gets them (longest estimated first)."""
    from rockmass.study import _longest_first, case_cost
    from rockmass.study_config import expand_cases, load_study

    document, raw = load_study(cfg)
    cases = expand_cases(document, raw, cfg)
    return [t["case"] for t in _longest_first([{"case": c.index, "cost": case_cost(c.document)}
                                               for c in cases])]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--cases", type=int, choices=sorted(SPACINGS), default=12)
    args = ap.parse_args()
    print(header("rockmass study: executor overhead and local speed-up"))
    rows = []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        cfg = _config(tmp, args.cases)
        order = _order(cfg)
        _run(_config(tmp, 6), tmp / "warm", 1)  # numba's on-disk cache up to date, files read once
        for rep in range(args.repeat):
            serial = _run(cfg, tmp / f"serial{rep}", 1)
            pool = _run(cfg, tmp / f"pool{rep}", 2)
            serial["overhead_fraction"] = serial["overhead_per_case_s"] / serial["mean_case_s"]
            times = [serial["case_times"][i] for i in order]
            by_index = [serial["case_times"][i] for i in sorted(serial["case_times"])]
            pool["speedup"] = serial["command_s"] / pool["command_s"]
            pool["run_speedup"] = serial["run_s"] / pool["run_s"]
            pool["ideal"] = sum(times) / _makespan(times, 2)
            pool["ideal_case_order"] = sum(by_index) / _makespan(by_index, 2)
            for r in (serial, pool):
                r["rep"] = rep
            rows += [serial, pool]
    columns = [("rep", "d"), ("workers", "d"), ("cases", "d"), ("load_before", ".2f"),
               ("load_after", ".2f"), ("command_s", ".2f"), ("run_s", ".2f"), ("case_sum_s", ".2f"),
               ("case_cpu_s", ".2f"), ("startup_s", ".2f"), ("overhead_fraction", ".1%"),
               ("speedup", ".2f"), ("ideal", ".2f"), ("ideal_case_order", ".2f"),
               ("run_speedup", ".2f")]
    print(table(rows, columns))
    print(f"pool order (longest estimated first): cases {order}; numba threads per task "
          f"{rows[1]['numba_threads']}, warm-ups per worker {rows[1]['warmups']}; "
          f"{os.cpu_count()} cores; targets: overhead <= 5 % of a case, speed-up >= 1.7")
    # one entry per case set, the others kept from earlier runs
    from _common import RESULTS

    try:
        saved = json.loads((RESULTS / "bench_study.json").read_text())["by_cases"]
    except (OSError, ValueError, KeyError):
        saved = {}
    saved[str(args.cases)] = {"rows": rows, "pool_order": order, "cpu_count": os.cpu_count(),
                              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    path = save("bench_study", {"by_cases": dict(sorted(saved.items(), key=lambda kv: int(kv[0])))})
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
