"""``rockmass run samples/quickstart.toml``: time of each stage, first run, warm run and reuse run.

    python benchmarks/bench_run.py [--config samples/quickstart.toml] [--repeat 3]

Each run is the command a user types (a fresh ``python -m rockmass run`` process), timed from the
outside (process wall time and CPU time, imports included) and per stage from its ``run.json``.
All three runs of a round use one numba cache folder (``NUMBA_CACHE_DIR``), new and empty at the
start of the round, so "warm" reads exactly the cache that "cold" filled:

- ``cold``: first run with the empty cache, as on a fresh install: every kernel a stage needs is
  compiled (and written to the cache);
- ``warm``: a new process, first run into a new folder, reading the kernels the cold run cached
  (every later project);
- ``reuse``: the same command again on the warm run's folder: every stage is reused (its hash
  unchanged), only run.json, report.html and manifest.json are rewritten.

With ``--repeat N`` the rounds run N times one after another and every figure is the median over
the rounds (2 shared cores: one round is at the mercy of the other users). Prints the table with the
cold / warm ratio per stage and in total (target: cold ≤ 1.5 × warm) and writes
``benchmarks/results/bench_run.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import header, save, table

ROOT = Path(__file__).resolve().parents[1]
KINDS = ("cold", "warm", "reuse")
TARGET_RATIO = 1.5


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run(config: Path, out: Path, env: dict) -> tuple[float, float, dict]:
    """(process wall s, process CPU s, run.json as printed by --json) of one ``rockmass run``."""
    cpu0 = _children_cpu()
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "rockmass", "run", str(config), "--out", str(out),
                           "--json"], capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    cpu = _children_cpu() - cpu0
    if proc.returncode != 0:
        raise SystemExit(f"rockmass run failed ({proc.returncode}):\n{proc.stderr}")
    return wall, cpu, json.loads(proc.stdout)


def _folder_size(path: Path) -> tuple[int, int]:
    files = [p for p in path.rglob("*") if p.is_file()]
    return len(files), sum(p.stat().st_size for p in files)


def _round(config: Path, env: dict) -> dict:
    """One cold / warm / reuse round with a new, empty numba cache folder."""
    with tempfile.TemporaryDirectory(prefix="bench_run_") as tmp:
        tmp = Path(tmp)
        cache = tmp / "numba_cache"
        cache.mkdir()
        round_env = {**env, "NUMBA_CACHE_DIR": str(cache)}
        runs = {"cold": _run(config, tmp / "cold", round_env)}
        n_files, n_bytes = _folder_size(cache)
        runs["warm"] = _run(config, tmp / "warm", round_env)
        runs["reuse"] = _run(config, tmp / "warm", round_env)
    return {"runs": runs, "cache_files": n_files, "cache_bytes": n_bytes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=str(ROOT / "samples" / "quickstart.toml"))
    parser.add_argument("--repeat", type=int, default=1, help="rounds; figures are medians")
    args = parser.parse_args()
    config = Path(args.config).resolve()
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["ROCKMASS_QUIET"] = "1"
    load_before = os.getloadavg()
    rounds = [_round(config, env) for _ in range(max(args.repeat, 1))]
    load_after = os.getloadavg()

    def median(values):
        return statistics.median(values)

    stages = [s["name"] for s in rounds[0]["runs"]["warm"][2]["stages"]]
    rows = []
    for name in stages:
        row = {"stage": name}
        for kind in KINDS:
            entries = [next(s for s in r["runs"][kind][2]["stages"] if s["name"] == name)
                       for r in rounds]
            row[f"{kind}_s"] = median([e["wall_s"] for e in entries])
            row[f"{kind}_status"] = entries[0]["status"]
        row["cold/warm"] = row["cold_s"] / row["warm_s"] if row["warm_s"] > 0 else None
        rows.append(row)
    total = {"stage": "stages total"}
    wall = {"stage": "process wall"}
    cpu = {"stage": "process CPU"}
    for kind in KINDS:
        total[f"{kind}_s"] = median([r["runs"][kind][2]["total_wall_s"] for r in rounds])
        wall[f"{kind}_s"] = median([r["runs"][kind][0] for r in rounds])
        cpu[f"{kind}_s"] = median([r["runs"][kind][1] for r in rounds])
    for row in (total, wall, cpu):
        row["cold/warm"] = row["cold_s"] / row["warm_s"]
    rows += [total, wall, cpu]
    name = config.relative_to(ROOT) if config.is_relative_to(ROOT) else config
    print(header(f"rockmass run {name}: time by stage (s), median of {len(rounds)} round(s); "
                 "cold = empty numba cache, warm = the cache the cold run filled, reuse = stages "
                 "reused"))
    print(table(rows, [("stage", "s"), ("cold_s", ".2f"), ("warm_s", ".2f"), ("cold/warm", ".2f"),
                       ("reuse_s", ".3f"), ("reuse_status", "s")]))
    ratio = wall["cold/warm"]
    print(f"process wall cold / warm = {ratio:.2f} (target <= {TARGET_RATIO}: "
          f"{'met' if ratio <= TARGET_RATIO else 'not met'}); process CPU cold / warm = "
          f"{cpu['cold/warm']:.2f}; numba cache after the cold run: "
          f"{median([r['cache_files'] for r in rounds]):.0f} files, "
          f"{median([r['cache_bytes'] for r in rounds]) / 1e6:.1f} MB; "
          f"load average {load_before[0]:.1f} -> {load_after[0]:.1f}")
    path = save("bench_run", {
        "config": str(config), "rounds": len(rounds), "rows": rows,
        "cold_over_warm_wall": ratio, "cold_over_warm_cpu": cpu["cold/warm"],
        "target_cold_over_warm": TARGET_RATIO,
        "per_round": [{kind: {"wall_s": r["runs"][kind][0], "cpu_s": r["runs"][kind][1],
                              "stages_s": {s["name"]: s["wall_s"]
                                           for s in r["runs"][kind][2]["stages"]}}
                       for kind in KINDS} | {"cache_files": r["cache_files"],
                                             "cache_bytes": r["cache_bytes"]}
                      for r in rounds],
        "load_average": {"before": load_before, "after": load_after}})
    print(f"written {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
