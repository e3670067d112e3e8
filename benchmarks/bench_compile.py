"""Numba compile time of every kernel a ``rockmass run`` compiles on a fresh install.

    python benchmarks/bench_compile.py [--config samples/quickstart.toml]

Runs the config once in this process with an empty numba cache (``NUMBA_CACHE_DIR`` set to a new
folder before numba is imported) and listens to numba's compile events. Each kernel's own compile
time is CPU time of the compiling thread (robust on shared cores), without the project kernels it
calls (they have their own row) but with the numba library functions it pulls in (sorting,
array expressions, string formatting for error messages: named in the last column, the heaviest
first); the stage is the ``rockmass run`` stage that was running. A kernel compiled for more than
one type signature shows the count: each one is a whole compilation. Prints the table, the totals
per stage and writes ``benchmarks/results/bench_compile.json``.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROJECT = ("rockmass.", "solver.", "dfn.", "fractal.", "imaging.", "blockgen.")


class _StageTracker:
    """A stderr stand-in that remembers the stage ``rockmass run`` announced last."""

    def __init__(self, stream):
        self.stream = stream
        self.stage = "start-up"

    def write(self, text):
        if "running " in text:
            self.stage = text.split("running ", 1)[1].split()[0]
        return len(text)

    def flush(self):
        pass

    def isatty(self):
        return False


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=str(ROOT / "samples" / "quickstart.toml"))
    args = parser.parse_args()
    workdir = tempfile.TemporaryDirectory(prefix="bench_compile_")  # removed when the script ends
    os.environ["NUMBA_CACHE_DIR"] = os.path.join(workdir.name, "numba_cache")
    os.environ.pop("ROCKMASS_QUIET", None)
    import numba.core.event as ev

    stack = []  # [name, start, time of project kernels compiled inside]
    own = collections.defaultdict(float)
    stage_of = {}
    sigs = collections.defaultdict(set)
    lib = collections.defaultdict(lambda: collections.defaultdict(float))
    tracker = _StageTracker(sys.stderr)

    def name_of(event):
        f = event.data["dispatcher"].py_func
        return f"{f.__module__.removeprefix('rockmass.')}.{f.__name__}"

    class Listener(ev.Listener):
        def on_start(self, event):
            stack.append([name_of(event), time.thread_time(), 0.0])

        def on_end(self, event):
            name, t0, inner = stack.pop()
            spent = time.thread_time() - t0
            sigs[name].add(str(event.data["args"]))
            if name.startswith(PROJECT) or not stack:
                own[name] += spent - inner
                stage_of.setdefault(name, tracker.stage)
                if stack:
                    stack[-1][2] += spent
            else:  # a numba library function: its time stays with the project kernel calling it
                caller = next((s[0] for s in reversed(stack) if s[0].startswith(PROJECT)), "?")
                lib[caller][name] += spent - inner
                stack[-1][2] += inner

    ev.register("numba:compile", Listener())
    out = os.path.join(workdir.name, "out")
    saved, sys.stderr = sys.stderr, tracker
    cpu0 = time.process_time()
    try:
        from rockmass.cli import main as cli

        rc = cli(["run", args.config, "--out", out, "--force"])
    finally:
        sys.stderr = saved
    cpu = time.process_time() - cpu0
    if rc != 0:
        raise SystemExit(f"rockmass run failed with exit code {rc}")

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _common import header, save, table

    rows = []
    for name in sorted(own, key=lambda k: -own[k]):
        pulled = sorted(lib[name].items(), key=lambda kv: -kv[1])
        rows.append({"kernel": name, "stage": stage_of[name], "signatures": len(sigs[name]),
                     "compile_s": own[name],
                     "numba_library": ", ".join(n.split(".", 1)[-1] for n, _ in pulled[:3])})
    per_stage = collections.defaultdict(float)
    for row in rows:
        per_stage[row["stage"]] += row["compile_s"]
    total = sum(per_stage.values())
    config = Path(args.config).resolve()
    name = config.relative_to(ROOT) if config.is_relative_to(ROOT) else config
    print(header(f"numba compile time of rockmass run {name} with an empty cache "
                 "(CPU s of the compiling thread)"))
    print(table([r for r in rows if r["compile_s"] >= 0.05],
                [("kernel", "s"), ("stage", "s"), ("signatures", "d"), ("compile_s", ".2f"),
                 ("numba_library", "s")]))
    print(f"({sum(r['compile_s'] < 0.05 for r in rows)} kernels under 0.05 s not shown)")
    print("per stage: " + ", ".join(f"{s} {t:.2f}" for s, t in per_stage.items())
          + f"; total compile {total:.2f} s of {cpu:.2f} s process CPU "
          f"({100 * total / cpu:.0f} %); {len(rows)} kernels, "
          f"{sum(r['signatures'] > 1 for r in rows)} compiled for more than one signature")
    path = save("bench_compile", {"config": str(config), "process_cpu_s": cpu,
                                  "compile_s": total, "per_stage_s": dict(per_stage),
                                  "kernels": rows,
                                  "load_average": os.getloadavg()})
    print(f"written {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
