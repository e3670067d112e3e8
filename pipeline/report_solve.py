"""The block-model and solver sections of ``report.html`` (:mod:`rockmass.run_report`): the block
model, the DEM stages, the monitored histories and the energy ledger (the maps of the final state are
in :mod:`rockmass.report_solve_maps`).
"""

from __future__ import annotations

import csv
import html
import math
from pathlib import Path
from typing import TYPE_CHECKING

from .html_report import figure, fmt, note, png_base64, pyplot, table
from .report_files import _image, _Note, _rel

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


def _section_blocks(run: _Run) -> str:
    """The block plot and the model's counts."""
    parts = [_image(run, "blocks", "blocks.png", "Block model (excavation stages shaded; edges coloured "
                                                  "by joint set)")]
    try:
        q = run.json("blocks", "blocks.json").get("quality") or {}
        rows = [[str(k), fmt(v)] for k, v in (q.get("n_blocks_by_region") or {}).items()]
        parts.append(table(["region", "blocks"], rows, "t-blocks"))
    except _Note as exc:
        parts.append(note(f"{exc}."))
    return "".join(parts)


def _section_solver(run: _Run) -> str:
    """Per DEM stage: steps, time step, convergence, unbalanced-force ratio, displacements."""
    r = run.json("solve", "result.json")
    rows = [[str(s.get("name", "")), str(s.get("kind", "")), str(s.get("status", "")), fmt(s.get("steps")),
             fmt(s.get("time_step_s")), fmt(s.get("simulated_time_s")), fmt(s.get("converged")),
             fmt(s.get("unbalanced_ratio")),
             f"{fmt(s.get('worst_ratio'))} (block {fmt(s.get('worst_block'))})",
             fmt(s.get("max_displacement_equilibrium_m")),
             fmt(s.get("max_displacement_boundary_equilibrium_m")),
             ", ".join(f"{k} {fmt(v)}" for k, v in (s.get("monitors") or {}).items()),
             _failed_text(s.get("failed_blocks") or []), fmt(s.get("slipping_contacts"))]
            for s in r.get("stages") or []]
    head = ["stage", "kind", "status", "steps", "dt (s)", "simulated time (s)", "converged",
            "unbalanced ratio", "worst block ratio", "max displacement (m)",
            "max displacement, boundary (m)", "boundary points (m)", "failed blocks",
            "slipping contacts"]
    status = f"Run status: {r.get('status')}" + (f" — {r['diagnostic']}" if r.get("diagnostic") else "")
    status += f"; largest displacement {fmt(r.get('max_displacement_m'))} m."
    return f"<p>{html.escape(status)}</p>" + table(head, rows, "t-solver")


def _failed_text(failed: list) -> str:
    """'3: fall 1, slide 2 (12.4 m²)' for a stage's failed blocks, '0' for none."""
    from .solver.failure import mechanism_counts

    if not failed:
        return "0"
    area = sum(float(f.get("area_m2", 0.0)) for f in failed)
    return (f"{len(failed)}: " + ", ".join(f"{k} {n}" for k, n in mechanism_counts(failed).items())
            + f" ({fmt(area)} m²)")


def _no_negative_zero(v):
    return v + 0.0 if isinstance(v, float) else v  # -0.0 + 0.0 is 0.0: a ledger shows "0", not "-0"


def _section_energy(run: _Run) -> str:
    """Energy ledger of every DEM stage (J): one row per term, one column per stage."""
    stages = [s for s in run.json("solve", "result.json").get("stages") or []
              if isinstance(s.get("energy"), dict)]
    if not stages:
        return note("result.json has no energy ledger.")
    terms = []
    for s in stages:
        terms += [k for k in s["energy"] if k not in terms]
    rows = [[t.removesuffix("_j")] + [fmt(_no_negative_zero(s["energy"].get(t))) for s in stages]
            for t in terms]
    return table(["term (J)"] + [str(s.get("name", "")) for s in stages], rows, "t-energy")


def _read_history(path: Path, out: Path) -> dict[str, list]:
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except FileNotFoundError:
        raise _Note(f"{_rel(path, out)} is missing") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise _Note(f"{_rel(path, out)} is not readable CSV ({exc})") from None
    if not rows or "time_s" not in rows[0]:
        raise _Note(f"{_rel(path, out)} has no rows or no time_s column")
    cols = {k: [r[k] for r in rows] for k in rows[0]}
    try:
        return {k: (v if k == "stage" else [float(x) for x in v]) for k, v in cols.items()}
    except (TypeError, ValueError) as exc:
        raise _Note(f"{_rel(path, out)} holds a value that is not a number ({exc})") from None


def _section_histories(run: _Run) -> str:
    """Monitored blocks over time (history.csv) and their final displacements (result.json)."""
    h = _read_history(run.dirs["solve"] / "history.csv", run.out)
    monitors = [k[:-5] for k in h if k.endswith("_ux_m") and f"{k[:-5]}_uy_m" in h]
    plt = pyplot()
    panels = 2 if "unbalanced_ratio" in h else 1
    fig, axes = plt.subplots(panels, 1, figsize=(7.5, 2.6 * panels + 0.6), sharex=True, squeeze=False)
    t = h["time_s"]
    ax = axes[0, 0]
    try:
        mons = run.json("solve", "result.json").get("monitors") or {}
    except _Note as exc:
        mons, missing = {}, exc
    else:
        missing = None
    for m in monitors:
        u = [1e3 * math.hypot(x, y) for x, y in zip(h[f"{m}_ux_m"], h[f"{m}_uy_m"])]
        failed = (mons.get(m) or {}).get("failed")
        if failed is None:
            ax.plot(t, u, label=m)
            continue
        end = _removal_row(h, failed)
        line, = ax.plot(t[:end + 1], u[:end + 1], label=f"{m} (failed: {failed['mechanism']}, taken out)")
        ax.plot([t[end]], [u[end]], "x", color=line.get_color())
    ax.set_ylabel("displacement (mm)")
    if monitors:
        ax.legend(frameon=False, fontsize=8)
    if panels == 2:
        ratio = [v if v > 0 else math.nan for v in h["unbalanced_ratio"]]
        axes[1, 0].plot(t, ratio, color="k", lw=0.8)
        if any(v > 0 for v in h["unbalanced_ratio"]):
            axes[1, 0].set_yscale("log")
        axes[1, 0].set_ylabel("unbalanced ratio")
    stages = h.get("stage") or []
    for i in range(1, len(stages)):
        if stages[i] != stages[i - 1]:
            for a in axes[:, 0]:
                a.axvline(t[i - 1], color="0.6", lw=0.8, ls="--")
    for a in axes[:, 0]:
        a.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time (s)")
    src = png_base64(fig)
    plt.close(fig)
    parts = [figure("Monitored blocks: displacement magnitude over time"
                    + (", and the unbalanced-force ratio" if panels == 2 else "")
                    + "; dashed lines: stage boundaries; a monitor whose block failed ends with a "
                    "cross where the block was taken out (a fall is not a displacement)", src)]
    if missing is not None:
        parts.append(note(f"{missing}."))
        return "".join(parts)
    rows = [[name, fmt(m.get("block")), fmt(m.get("final_ux_m")), fmt(m.get("final_uy_m")),
             fmt(m.get("final_displacement_m")) if "failed" not in m else
             f"failed in stage {m['failed']['stage']} ({m['failed']['mechanism']}): no displacement",
             fmt(m.get("max_contact_plastic_slip_m"))]
            for name, m in mons.items()]
    if rows:
        parts.append(table(["monitor", "block", "final ux (m)", "final uy (m)", "final |u| (m)",
                            "max plastic slip on its contacts (m)"], rows, "t-monitors"))
    return "".join(parts)


def _removal_row(history: dict, failed: dict) -> int:
    """The last history row of a failed monitor's block before it was taken out: the last row at
    or before ``failed["time_s"]`` (:class:`rockmass.solver.failure.FailedBlock`), or the last row
    of its stage for a result written before that time was recorded."""
    times, stages = history["time_s"], history["stage"]
    rows = [i for i, s in enumerate(stages) if s == failed["stage"]] or [len(times) - 1]
    removed = failed.get("time_s")
    if removed is None:
        return rows[-1]
    before = [i for i in rows if times[i] <= removed]
    return before[-1] if before else rows[0]
