"""Static stages: steps, run time and displacement error with and without density scaling of the
rigid blocks (``[solve] density_scaling``, docs/dem.md §10.4).

    python benchmarks/bench_static_steps.py [--quick]

Models: the quickstart's solve (samples/quickstart.toml: its blocks, built by ``rockmass run`` into
a cache folder under the system temp folder and reused on later runs, and its [solve] section
without ``density_scaling``) and, unless ``--quick``, the seed-000 cavern of
samples/solve_cavern.toml (excavation in three stages). Each is solved three ways: ``plain`` at
the sample's tolerances, ``scaled`` (density scaling, the same tolerances) and ``reference``
(plain at an unbalanced ratio of 1e-7 and a block ratio of 1e-5: today's converged answer,
converged further). Per row: the static steps of all stages, the wall time of the run (each
model is run once first, so no row pays compilation), the first stage's time step, and the
error against the reference of every monitor point and of the largest block displacement after
the last stage, in % of the reference value (the largest over the monitors, and the largest
displacement's) and, for the monitors, in µm (a wall that moves 4 µm shows a 0.4 µm difference
as 10 %), and the blocks that failed (kept moving and were taken out). Frictional equilibria depend on the path, and density scaling changes the path:
its error is the price of the speed.

Rows also go to benchmarks/results/bench_static_steps.json.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE))
from _common import header, save, table  # noqa: E402

ROOT = _HERE.parent
TIGHT, TIGHT_BLOCK = 1e-7, 1e-5


def quickstart_case():
    """(label, model, settings) of the quickstart's solve stage."""
    from rockmass.solve_stage import prepare, read_blocks_file

    out = Path(tempfile.gettempdir()) / "rockmass_bench_static_steps_quickstart"
    subprocess.run([sys.executable, "-m", "rockmass", "run", str(ROOT / "samples/quickstart.toml"),
                    "--out", str(out)], check=True, capture_output=True)
    model = read_blocks_file(out / "blocks" / "blocks.json")
    _doc, model, settings, _i, _t = prepare(ROOT / "samples/quickstart.toml", model=model)
    return "quickstart", model, settings


def cavern_case():
    from rockmass.solve_stage import prepare

    _doc, model, settings, _i, _t = prepare(ROOT / "samples/solve_cavern.toml")
    return "seed-000 cavern", model, settings


def variants(settings):
    """The three ways each model is solved (module docstring)."""
    plain = replace(settings, density_scaling=False)
    tight = tuple(replace(s, tolerance=TIGHT, block_tolerance=TIGHT_BLOCK,
                          max_steps=max(s.max_steps, 400_000)) for s in plain.stages)
    return {"plain": plain, "scaled": replace(plain, density_scaling=True),
            "reference": replace(plain, stages=tight)}


def measures(result) -> dict:
    last = result.stages[-1]
    return {"monitors": dict(last.monitors), "max_disp": last.max_displacement_m}


def rows_for(label, model, settings) -> list[dict]:
    from rockmass.solver import run

    runs = {}
    for name, s in variants(settings).items():
        run(model, s)  # the first run of each compiles what it needs; the second is timed
        t0 = time.perf_counter()
        r = run(model, s)
        runs[name] = (r, time.perf_counter() - t0)
    ref = measures(runs["reference"][0])
    rows = []
    for name, (r, secs) in runs.items():
        m = measures(r)
        common = sorted(set(m["monitors"]) & set(ref["monitors"]))
        err_mon = max((abs(m["monitors"][k] / ref["monitors"][k] - 1) for k in common
                       if ref["monitors"][k] != 0), default=None)
        err_abs = max((abs(m["monitors"][k] - ref["monitors"][k]) for k in common), default=None)
        rows.append({"model": label, "setting": name, "status": r.status,
                     "steps": sum(st.steps for st in r.stages), "wall_s": secs,
                     "dt_first_s": r.stages[0].time_step_s,
                     "failed_blocks": sum(len(st.failed_blocks) for st in r.stages),
                     "speedup": runs["plain"][1] / secs,
                     "monitor_error_pct": None if err_mon is None else 100 * err_mon,
                     "monitor_error_um": None if err_abs is None else 1e6 * err_abs,
                     "max_disp_error_pct": 100 * abs(m["max_disp"] / ref["max_disp"] - 1),
                     "monitors": ",".join(common)})
    return rows


def main(quick: bool = False) -> None:
    print(header("static stages: density scaling — steps and time against displacement error"))
    cases = [quickstart_case()] + ([] if quick else [cavern_case()])
    rows = [row for case in cases for row in rows_for(*case)]
    print(table(rows, [("model", "s"), ("setting", "s"), ("status", "s"), ("steps", "d"),
                       ("wall_s", ".2f"), ("speedup", ".2f"), ("dt_first_s", ".3g"),
                       ("failed_blocks", "d"),
                       ("monitor_error_pct", ".3f"), ("monitor_error_um", ".2f"),
                       ("max_disp_error_pct", ".3f"),
                       ("monitors", "s")]))
    save("bench_static_steps", {"rows": rows})


if __name__ == "__main__":
    main(quick="--quick" in sys.argv[1:])
