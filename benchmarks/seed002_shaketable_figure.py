"""Seed 002 shake table (Ahola et al. 1996, as Varma et al. 2019 modelled it): the slip of the
top-left block of the tunnel against the cycle, beside the experiment and Newmark's sliding block.

    python benchmarks/seed002_shaketable_figure.py [--png docs/figures/seed002_shaketable_slip.png]
        [--passes-png docs/figures/seed002_record_passes.png]

Reads what ``benchmarks/bench_shaketable.py`` saved (no new run): Table 4 (15 cycles at the 15.5 mm
amplitude of the experiment, 2.94 Hz, ``results/bench_shaketable_tables4.json``) and Table 7 (eight
cycles at peak table accelerations of 1.14, 1.2, 1.3 and 1.6 times the model's pseudo-static
critical acceleration a_c, with the slip of a rigid block sliding one way above a constant a_c
under the same table motion, Newmark 1965; ``results/bench_shaketable_tables7.json``). Prints the
slip per cycle and draws two panels: left, the accumulated slip with the experiment's 4.5 mm and
UDEC's 3.9 mm after 15 cycles (seed 002 Fig. 8) and the straight line of 4.5 mm spread evenly over
the 15 cycles; right, the slip of each cycle (log scale) against Newmark's. What the figure shows
is the model's slip per cycle dying away near the threshold where Newmark's block and the
experiment keep slipping (docs/dem.md §13, problem 16).

``--passes-png`` draws the record passes of Tables 15b, 16 and 18 (``results/
bench_shaketable_tables15.json``, ``...16.json``, ``...18.json``): the slip of the top-left block in
each 10 s pass of a 0.6-6 Hz band record, beside Newmark's block under the same record and the
experiment's mean of 0.3 mm a pass (4.5 mm over 15 passes).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
EXPERIMENT_MM, UDEC_MM, CYCLES = 4.5, 3.9, 15


def read_tables(results: Path = RESULTS) -> tuple[list[dict], dict[float, list[dict]]]:
    """(Table 4 rows: cycle, slip_mm; Table 7 rows by a_max / a_c: cycle, slip_mm, increment_mm,
    newmark_mm, status)."""
    table4 = json.loads((results / "bench_shaketable_tables4.json").read_text())
    fifteen = table4["fifteen_cycles"]["chosen"]["rows"]
    table7 = json.loads((results / "bench_shaketable_tables7.json").read_text())["accumulation"]
    by_level: dict[float, list[dict]] = {}
    for row in table7:
        by_level.setdefault(round(row["a_max_over_a_c"], 2), []).append(row)
    return fifteen, by_level


def newmark_increments(rows: list[dict]) -> list[float]:
    """Newmark's slip of each cycle from the accumulated column."""
    totals = [r["newmark_mm"] for r in rows]
    return [b - a for a, b in zip([0.0] + totals[:-1], totals)]


def draw(fifteen, by_level, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.4))
    colours = {1.14: "tab:blue", 1.2: "tab:orange", 1.3: "tab:red", 1.6: "tab:purple"}
    left.plot([r["cycle"] for r in fifteen], [r["slip_mm"] for r in fifteen], "o-", color="k",
              label="model, 15.5 mm at 2.94 Hz (1.14 a_c; Table 4)")
    for level, rows in sorted(by_level.items()):
        done = [r for r in rows if r["slip_mm"] is not None and r["slip_mm"] < 30.0]
        colour = colours.get(level, "tab:gray")
        if level != 1.14:
            left.plot([r["cycle"] for r in done], [r["slip_mm"] for r in done], "o-", color=colour,
                      label=f"model, {level:g} a_c" + (" (then collapse)" if len(done) < len(rows)
                                                        else ""))
        left.plot([r["cycle"] for r in rows], [r["newmark_mm"] for r in rows], "--", color=colour,
                  alpha=0.6)
        cycles = [r["cycle"] for r in rows if r["increment_mm"] is not None]
        increments = [max(r["increment_mm"], 1e-4) for r in rows if r["increment_mm"] is not None]
        right.semilogy(cycles, increments, "o-", color=colour, label=f"model, {level:g} a_c")
        right.semilogy([r["cycle"] for r in rows], [max(v, 1e-4) for v in newmark_increments(rows)],
                       "--", color=colour, alpha=0.6)
    left.plot([0, CYCLES], [0, EXPERIMENT_MM], ":", color="tab:green",
              label="4.5 mm spread evenly over 15 cycles")
    left.plot([CYCLES], [EXPERIMENT_MM], "*", ms=14, color="tab:green", label="experiment, 4.5 mm")
    left.plot([CYCLES], [UDEC_MM], "s", ms=8, color="tab:brown", label="UDEC (seed 002), 3.9 mm")
    right.axhline(EXPERIMENT_MM / CYCLES, ls=":", color="tab:green", label="experiment, mean per cycle")
    left.set(xlabel="cycle", ylabel="slip of the top-left block, mm", ylim=(0, 16), xlim=(0, 16),
             title="accumulated slip (dashed: Newmark, same colour)")
    right.set(xlabel="cycle", ylabel="slip in the cycle, mm", ylim=(1e-4, 30), xlim=(0, 9),
              title="slip per cycle (dashed: Newmark; cycles 1 and 8 ramp up and down)")
    left.legend(fontsize=7, loc="upper left")
    right.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


#: (results file, key, label) of the record-pass runs of bench_shaketable.py
PASS_RUNS = (("bench_shaketable_tables15.json", "record_at_15p5mm",
              "record at 15.5 mm (0.12 g), Coulomb (Table 15b)"),
             ("bench_shaketable_tables18.json", "record_at_15p5mm_yielding",
              "record at 15.5 mm, continuously yielding (Table 18)"),
             ("bench_shaketable_tables16.json", "record_passes_yielding",
              "record at 1.14 a_c (0.54 g), continuously yielding (Table 16)"))


def read_passes(results: Path = RESULTS) -> list[tuple[str, list[float], list[float]]]:
    """Per run of :data:`PASS_RUNS`: (label, slip in each pass, Newmark's slip in each pass), mm."""
    runs = []
    for name, key, label in PASS_RUNS:
        rows = json.loads((results / name).read_text())[key]["rows"]
        slips = [r["slip_mm"] for r in rows if r["slip_mm"] is not None]
        newmark = [r["newmark_mm"] for r in rows][:len(slips)]
        runs.append((label, per_step(slips), per_step(newmark)))
    return runs


def per_step(totals: list[float]) -> list[float]:
    """Increments of an accumulated series."""
    return [b - a for a, b in zip([0.0] + totals[:-1], totals)]


def draw_passes(runs, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.2))
    colours = ("tab:blue", "tab:orange", "tab:red")
    width = 0.8 / len(runs)
    for k, ((label, slips, newmark), colour) in enumerate(zip(runs, colours)):
        x = [p + 1 + (k - (len(runs) - 1) / 2) * width for p in range(len(slips))]
        ax.bar(x, [max(v, 1e-4) for v in slips], width, color=colour, label=f"model, {label}")
        ax.plot(x, [max(v, 1e-4) for v in newmark], "_", ms=18, mew=2, color=colour)
    ax.plot([], [], "_", ms=18, mew=2, color="k",
            label="Newmark's block at a_c under the same record, same colour (0 at 15.5 mm)")
    ax.axhline(EXPERIMENT_MM / CYCLES, ls=":", color="tab:green",
               label="experiment, 4.5 mm over 15 passes: mean per pass")
    ax.set_yscale("log")
    ax.set(xlabel="pass of the 10 s record", ylabel="slip of the top-left block in the pass, mm",
           ylim=(1e-3, 3), xticks=[1, 2],
           title="slip in each pass of a 0.6-6 Hz band record (10 s)")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=1)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--png", type=Path, default=None, help="where to draw the figure")
    parser.add_argument("--passes-png", type=Path, default=None,
                        help="where to draw the record passes of Tables 15b, 16 and 18")
    args = parser.parse_args(argv)
    fifteen, by_level = read_tables()
    print("Table 4, 15.5 mm at 2.94 Hz: slip after each cycle, mm")
    print("  " + " ".join(f"{r['slip_mm']:.3f}" for r in fifteen))
    print(f"  after {CYCLES}: {fifteen[-1]['slip_mm']:.2f} mm; experiment {EXPERIMENT_MM} mm "
          f"({100 * (fifteen[-1]['slip_mm'] / EXPERIMENT_MM - 1):+.0f} %), UDEC {UDEC_MM} mm")
    print("Table 7: slip in each cycle, mm (Newmark's in brackets)")
    for level, rows in sorted(by_level.items()):
        cells = [f"{r['increment_mm']:.3f} ({n:.2f})" if r["increment_mm"] is not None else "-"
                 for r, n in zip(rows, newmark_increments(rows))]
        print(f"  {level:g} a_c: " + "  ".join(cells))
    if args.png:
        draw(fifteen, by_level, args.png)
        print(f"figure written to {args.png}")
    runs = read_passes()
    print("Tables 15b, 18, 16: slip in each 10 s pass of the record, mm (Newmark's in brackets)")
    for label, slips, newmark in runs:
        print(f"  {label}: " + "  ".join(f"{v:.3f} ({n:.3f})" for v, n in zip(slips, newmark)))
    if args.passes_png:
        draw_passes(runs, args.passes_png)
        print(f"figure written to {args.passes_png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
