"""``rockmass run samples/quickstart.toml`` by stage: cold, after ``rockmass warmup``, warm, reuse.

    python benchmarks/bench_run.py [--config samples/quickstart.toml] [--repeat 3] [--warmup-workers N]

Each run is the command a user types (a fresh ``python -m rockmass ...`` process), timed from the
outside (process wall time and CPU time, imports included) and per stage from its ``run.json``.
A round measures, interleaved, two fresh installs, each with a numba cache folder
(``NUMBA_CACHE_DIR``) of its own, new and empty at its start:

- install 1, ``cold``: first run with the empty cache, no warmup: every kernel a stage needs is
  compiled (and written to the cache); then ``warm``: a new process, first run into a new folder,
  reading the kernels the cold run cached (every later project); then ``reuse``: the same command
  again on the warm run's folder: every stage is reused (its hash unchanged), only run.json,
  report.html and manifest.json are rewritten;
- install 2, ``warmup``: ``rockmass warmup`` (its own process(es): wall and CPU time, children
  included) with the empty cache; then ``first``: the first run after it.

The two installs alternate which goes first from round to round. With ``--repeat N`` every figure
is the median over the rounds (2 shared cores: one round is at the mercy of the other users).
Prints the table by stage, the processes' wall and CPU times with the ratios first / warm
(target: <= 1.5) and cold / warm, and writes ``benchmarks/results/bench_run.json``.
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
KINDS = ("cold", "first", "warm", "reuse")  # the runs of a round (``first``: after warmup)
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


def _warmup(env: dict, workers: int | None) -> tuple[float, float, list[str]]:
    """(wall s, CPU s of it and its workers, printed lines) of one ``rockmass warmup``."""
    cpu0 = _children_cpu()
    t0 = time.perf_counter()
    extra = [] if workers is None else ["--workers", str(workers)]
    proc = subprocess.run([sys.executable, "-m", "rockmass", "warmup", *extra], capture_output=True,
                          text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    cpu = _children_cpu() - cpu0
    if proc.returncode != 0:
        raise SystemExit(f"rockmass warmup failed ({proc.returncode}):\n{proc.stderr}")
    return wall, cpu, proc.stdout.splitlines()


def _folder_size(path: Path) -> tuple[int, int]:
    files = [p for p in path.rglob("*") if p.is_file()]
    return len(files), sum(p.stat().st_size for p in files)


def _fresh_cache(tmp: Path, name: str, env: dict) -> tuple[Path, dict]:
    """A new, empty numba cache folder under ``tmp`` and the environment that uses it."""
    cache = tmp / name
    cache.mkdir()
    return cache, {**env, "NUMBA_CACHE_DIR": str(cache)}


def _cold_warm_reuse(config: Path, tmp: Path, env: dict) -> dict:
    """Install 1: cold, warm and reuse runs on one new cache; the cache's size after cold."""
    cache, env = _fresh_cache(tmp, "cache_cold", env)
    runs = {"cold": _run(config, tmp / "cold", env)}
    n_files, n_bytes = _folder_size(cache)
    runs["warm"] = _run(config, tmp / "warm", env)
    runs["reuse"] = _run(config, tmp / "warm", env)
    return {"runs": runs, "cache_files": n_files, "cache_bytes": n_bytes}


def _warmup_first(config: Path, tmp: Path, env: dict, workers: int | None) -> dict:
    """Install 2: ``rockmass warmup`` on a new cache, then the first run; the cache's size after
    the warmup."""
    cache, env = _fresh_cache(tmp, "cache_warmup", env)
    warmup = _warmup(env, workers)
    n_files, n_bytes = _folder_size(cache)
    return {"runs": {"first": _run(config, tmp / "first", env)}, "warmup": warmup,
            "warmup_cache_files": n_files, "warmup_cache_bytes": n_bytes}


def _round(config: Path, env: dict, warmup_first: bool, workers: int | None) -> dict:
    """One round: both installs, in the order ``warmup_first`` says."""
    with tempfile.TemporaryDirectory(prefix="bench_run_") as tmp:
        tmp = Path(tmp)
        steps = [lambda: _cold_warm_reuse(config, tmp, env),
                 lambda: _warmup_first(config, tmp, env, workers)]
        one, two = [step() for step in (steps[::-1] if warmup_first else steps)]
    runs = {**one.pop("runs"), **two.pop("runs")}
    return {"runs": runs, **one, **two, "warmup_went_first": warmup_first}


def _stage_rows(rounds: list[dict]) -> list[dict]:
    """Per stage: median wall time of each run kind, its status, and the ratios to warm."""
    rows = []
    for name in [s["name"] for s in rounds[0]["runs"]["warm"][2]["stages"]]:
        row = {"stage": name}
        for kind in KINDS:
            entries = [next(s for s in r["runs"][kind][2]["stages"] if s["name"] == name)
                       for r in rounds]
            row[f"{kind}_s"] = statistics.median([e["wall_s"] for e in entries])
            row[f"{kind}_status"] = entries[0]["status"]
        _ratios(row)
        rows.append(row)
    return rows


def _ratios(row: dict) -> None:
    """``cold/warm`` and ``first/warm`` of a row (None when warm is 0)."""
    for kind in ("cold", "first"):
        row[f"{kind}/warm"] = row[f"{kind}_s"] / row["warm_s"] if row["warm_s"] > 0 else None


def _process_rows(rounds: list[dict]) -> list[dict]:
    """Stages total, process wall and process CPU of each run kind (medians), with ratios; the
    warmup's wall and CPU, and warmup + first run, in the ``first`` column."""
    median = statistics.median
    total = {"stage": "stages total"}
    wall = {"stage": "process wall"}
    cpu = {"stage": "process CPU"}
    for kind in KINDS:
        total[f"{kind}_s"] = median([r["runs"][kind][2]["total_wall_s"] for r in rounds])
        wall[f"{kind}_s"] = median([r["runs"][kind][0] for r in rounds])
        cpu[f"{kind}_s"] = median([r["runs"][kind][1] for r in rounds])
    for row in (total, wall, cpu):
        _ratios(row)
    warmup = {"stage": "warmup wall", "first_s": median([r["warmup"][0] for r in rounds])}
    warmup_cpu = {"stage": "warmup CPU", "first_s": median([r["warmup"][1] for r in rounds])}
    both = {"stage": "warmup + first wall",
            "first_s": median([r["warmup"][0] + r["runs"]["first"][0] for r in rounds])}
    return [total, wall, cpu, warmup, warmup_cpu, both]


def _summary(rows: dict, rounds: list[dict], load: tuple) -> str:
    """The closing lines: the ratios against the target, the caches' sizes, the load."""
    median = statistics.median
    first, cold = rows["process wall"]["first/warm"], rows["process wall"]["cold/warm"]
    return (f"process wall: first run after warmup / warm = {first:.2f} (target <= {TARGET_RATIO}: "
            f"{'met' if first <= TARGET_RATIO else 'not met'}); cold / warm = {cold:.2f} "
            f"({'met' if cold <= TARGET_RATIO else 'not met'} without warmup); process CPU: "
            f"first / warm = {rows['process CPU']['first/warm']:.2f}, cold / warm = "
            f"{rows['process CPU']['cold/warm']:.2f}\n"
            f"warmup {rows['warmup wall']['first_s']:.1f} s wall, "
            f"{rows['warmup CPU']['first_s']:.1f} CPU-s; numba cache after the cold run "
            f"{median([r['cache_files'] for r in rounds]):.0f} files, "
            f"{median([r['cache_bytes'] for r in rounds]) / 1e6:.1f} MB, after the warmup "
            f"{median([r['warmup_cache_files'] for r in rounds]):.0f} files, "
            f"{median([r['warmup_cache_bytes'] for r in rounds]) / 1e6:.1f} MB; "
            f"load average {load[0][0]:.1f} -> {load[1][0]:.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=str(ROOT / "samples" / "quickstart.toml"))
    parser.add_argument("--repeat", type=int, default=1, help="rounds; figures are medians")
    parser.add_argument("--warmup-workers", type=int, default=None, metavar="N",
                        help="rockmass warmup --workers N (default: its own default)")
    args = parser.parse_args()
    config = Path(args.config).resolve()
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["ROCKMASS_QUIET"] = "1"
    load_before = os.getloadavg()
    rounds = [_round(config, env, k % 2 == 1, args.warmup_workers)
              for k in range(max(args.repeat, 1))]
    load_after = os.getloadavg()

    rows = _stage_rows(rounds) + _process_rows(rounds)
    name = config.relative_to(ROOT) if config.is_relative_to(ROOT) else config
    print(header(f"rockmass run {name}: time by stage (s), median of {len(rounds)} round(s); "
                 "cold = empty numba cache, first = first run after rockmass warmup (its own "
                 "empty cache), warm = the cache the cold run filled, reuse = stages reused"))
    print(table(rows, [("stage", "s"), ("cold_s", ".2f"), ("first_s", ".2f"), ("warm_s", ".2f"),
                       ("cold/warm", ".2f"), ("first/warm", ".2f"), ("reuse_s", ".3f"),
                       ("reuse_status", "s")]))
    by_name = {r["stage"]: r for r in rows}
    print(_summary(by_name, rounds, (load_before, load_after)))
    path = save("bench_run", {
        "config": str(config), "rounds": len(rounds), "rows": rows,
        "first_over_warm_wall": by_name["process wall"]["first/warm"],
        "cold_over_warm_wall": by_name["process wall"]["cold/warm"],
        "first_over_warm_cpu": by_name["process CPU"]["first/warm"],
        "cold_over_warm_cpu": by_name["process CPU"]["cold/warm"],
        "target_over_warm": TARGET_RATIO,
        "warmup_workers": args.warmup_workers,
        "per_round": [{kind: {"wall_s": r["runs"][kind][0], "cpu_s": r["runs"][kind][1],
                              "stages_s": {s["name"]: s["wall_s"]
                                           for s in r["runs"][kind][2]["stages"]}}
                       for kind in KINDS}
                      | {"warmup": {"wall_s": r["warmup"][0], "cpu_s": r["warmup"][1],
                                    "output": r["warmup"][2]},
                         "warmup_went_first": r["warmup_went_first"],
                         "cache_files": r["cache_files"], "cache_bytes": r["cache_bytes"],
                         "warmup_cache_files": r["warmup_cache_files"],
                         "warmup_cache_bytes": r["warmup_cache_bytes"]}
                      for r in rounds],
        "load_average": {"before": load_before, "after": load_after}})
    print(f"written {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
