"""``rockmass run samples/quickstart.toml``: wall time of each stage, first run and reuse run.

    python benchmarks/bench_run.py [--config samples/quickstart.toml]

Each run is the command a user types (a fresh ``python -m rockmass run`` process), timed from the
outside (process wall time, imports included) and per stage from its ``run.json``:

- ``cold``: first run with an empty numba cache (``NUMBA_CACHE_DIR`` set to a new folder), as on a
  fresh clone: the solver's and imaging's kernels are compiled;
- ``warm``: first run into a new folder with the kernels cached (every later project);
- ``reuse``: the same command again on the warm run's folder: every stage is reused (its hash
  unchanged), only run.json, report.html and manifest.json are rewritten.

Prints a table and writes ``benchmarks/results/bench_run.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import header, save, table

ROOT = Path(__file__).resolve().parents[1]


def _run(config: Path, out: Path, env: dict) -> tuple[float, dict]:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "rockmass", "run", str(config), "--out", str(out), "--json"],
                          capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"rockmass run failed ({proc.returncode}):\n{proc.stderr}")
    return wall, json.loads(proc.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=str(ROOT / "samples" / "quickstart.toml"))
    args = parser.parse_args()
    config = Path(args.config).resolve()
    env = {**os.environ, "ROCKMASS_QUIET": "1"}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cold_env = {**env, "NUMBA_CACHE_DIR": str(tmp / "numba_cache")}
        runs = {"cold": _run(config, tmp / "cold", cold_env),
                "warm": _run(config, tmp / "warm", env)}
        runs["reuse"] = _run(config, tmp / "warm", env)
    stages = [s["name"] for s in runs["warm"][1]["stages"]]
    rows = []
    for name in stages:
        row = {"stage": name}
        for kind, (_, doc) in runs.items():
            entry = next(s for s in doc["stages"] if s["name"] == name)
            row[f"{kind}_s"] = entry["wall_s"]
            row[f"{kind}_status"] = entry["status"]
        rows.append(row)
    rows.append({"stage": "stages total", **{f"{k}_s": d["total_wall_s"] for k, (_, d) in runs.items()}})
    rows.append({"stage": "process wall", **{f"{k}_s": w for k, (w, _) in runs.items()}})
    print(header(f"rockmass run {config.relative_to(ROOT) if config.is_relative_to(ROOT) else config}: "
                 "wall time by stage (s)"))
    print(table(rows, [("stage", "s"), ("cold_s", ".2f"), ("warm_s", ".2f"), ("reuse_s", ".3f"),
                       ("reuse_status", "s")]))
    path = save("bench_run", {"config": str(config), "rows": rows,
                              "load_average": os.getloadavg() if hasattr(os, "getloadavg") else None})
    print(f"written {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
