"""Seed 000 study, Jiang et al. Figs. 7-8 in kind: figure and table from a study's results.csv.

    python benchmarks/seed000_study_figure.py out/study_seed000/results.csv [--png FIG.png]

Reads the results of ``rockmass study samples/study_seed000.toml`` (or ``study_cavern.toml``: one
alpha) and prints, per (theta, alpha, spacing), the cases by outcome, D_box and the maximum
displacement of the blocks in equilibrium (mean and range over the realizations whose outcome is
``ok`` or ``failed_blocks``), the failed blocks and the boundary points; then the trend checks of
Jiang et al. §4.2 (docs/sources.md §1): the slope of displacement against D_box per theta (Fig. 7: rising for theta < 90°,
flat for 90°) and the displacement against theta per alpha (Fig. 8: a peak at theta = 60° for
alpha = 0° and 60°). ``--png`` draws both: left, displacement against D_box per alpha (colour:
theta; dots: ok, crosses: blocks failed); right, mean displacement and failed blocks against theta.
"""

from __future__ import annotations

import csv
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

THETA = "blocks.two_sets.theta_deg"
ALPHA = "blocks.two_sets.alpha_deg"
SPACING = "blocks.two_sets.spacing_m"
IN_EQUILIBRIUM = ("ok", "failed_blocks")


def read(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        r["theta"] = float(r[THETA])
        r["alpha"] = float(r.get(ALPHA) or 0.0)
        r["spacing"] = r[SPACING]
        r["d_box"] = float(r["d_box"])
        r["disp_mm"] = (float(r["max_displacement_m"]) * 1e3
                        if r["status"] in IN_EQUILIBRIUM and r["max_displacement_m"] else np.nan)
        r["n_failed"] = int(r["failed_blocks"] or 0)
    return rows


def group_table(rows: list[dict]) -> list[dict]:
    groups = defaultdict(list)
    for r in rows:
        groups[(r["theta"], r["alpha"], r["spacing"])].append(r)
    out = []
    for (theta, alpha, spacing), rs in sorted(groups.items(), key=lambda kv: (kv[0][1], kv[0][0],
                                                                               kv[0][2])):
        d = np.array([r["disp_mm"] for r in rs])
        good = d[np.isfinite(d)]
        outcome = defaultdict(int)
        for r in rs:
            outcome[r["status"]] += 1
        out.append({"alpha": alpha, "theta": theta, "spacing": spacing,
                    "d_box": float(np.mean([r["d_box"] for r in rs])),
                    "cases": len(rs), "outcomes": dict(outcome),
                    "disp_mean_mm": float(good.mean()) if len(good) else np.nan,
                    "disp_min_mm": float(good.min()) if len(good) else np.nan,
                    "disp_max_mm": float(good.max()) if len(good) else np.nan,
                    "failed": sum(r["n_failed"] for r in rs),
                    "mechanisms": " ".join(r["failed_mechanisms"] for r in rs if r["failed_mechanisms"])})
    return out


def print_table(table: list[dict]):
    print(f"{'alpha':>5} {'theta':>5} {'spacing':>12} {'D_box':>6} {'outcomes':<32} "
          f"{'disp mean [min-max] mm':<24} failed blocks")
    for t in table:
        outc = ", ".join(f"{k} {v}" for k, v in sorted(t["outcomes"].items()))
        disp = (f"{t['disp_mean_mm']:.2f} [{t['disp_min_mm']:.2f}-{t['disp_max_mm']:.2f}]"
                if np.isfinite(t["disp_mean_mm"]) else "-")
        print(f"{t['alpha']:5.0f} {t['theta']:5.0f} {t['spacing']:>12} {t['d_box']:6.3f} {outc:<32} "
              f"{disp:<24} {t['failed']}")


def trends(rows: list[dict]):
    """Slope of displacement against D_box per (alpha, theta) over cases in equilibrium, and the
    theta of the largest mean displacement per alpha."""
    print("\nTrend 1 (Fig. 7): d(displacement)/d(D_box) per alpha, theta (cases in equilibrium)")
    for alpha in sorted({r["alpha"] for r in rows}):
        for theta in sorted({r["theta"] for r in rows}):
            sel = [r for r in rows if r["alpha"] == alpha and r["theta"] == theta
                   and np.isfinite(r["disp_mm"])]
            if len({r["d_box"] for r in sel}) < 2:
                continue
            x = np.array([r["d_box"] for r in sel])
            y = np.array([r["disp_mm"] for r in sel])
            slope = np.polyfit(x, y, 1)[0]
            rho = np.corrcoef(x, y)[0, 1]
            print(f"  alpha {alpha:4.0f}  theta {theta:4.0f}: {slope:+7.2f} mm per unit D_box, "
                  f"r = {rho:+.2f} ({len(sel)} cases)")
    print("\nTrend 2 (Fig. 8): mean displacement (mm) and failed blocks against theta, per alpha")
    for alpha in sorted({r["alpha"] for r in rows}):
        parts = []
        for theta in sorted({r["theta"] for r in rows}):
            sel = [r for r in rows if r["alpha"] == alpha and r["theta"] == theta]
            d = np.array([r["disp_mm"] for r in sel])
            parts.append(f"theta {theta:.0f}: {np.nanmean(d) if np.isfinite(d).any() else np.nan:.2f} mm, "
                         f"{sum(r['n_failed'] for r in sel)} failed")
        print(f"  alpha {alpha:4.0f}: " + "; ".join(parts))


def figure(rows: list[dict], png: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    alphas = sorted({r["alpha"] for r in rows})
    thetas = sorted({r["theta"] for r in rows})
    colours = dict(zip(thetas, ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange")))
    fig, axes = plt.subplots(1, len(alphas) + 1, figsize=(4.2 * (len(alphas) + 1), 3.8))
    for ax, alpha in zip(axes, alphas):
        for theta in thetas:
            sel = [r for r in rows if r["alpha"] == alpha and r["theta"] == theta]
            ok = [r for r in sel if r["status"] == "ok"]
            fb = [r for r in sel if r["status"] == "failed_blocks"]
            ax.plot([r["d_box"] for r in ok], [r["disp_mm"] for r in ok], "o",
                    color=colours[theta], label=f"θ = {theta:.0f}°")
            ax.plot([r["d_box"] for r in fb], [r["disp_mm"] for r in fb], "x",
                    color=colours[theta], ms=8)
        ax.set_title(f"α = {alpha:.0f}° (x: blocks failed, rest in equilibrium)", fontsize=9)
        ax.set_xlabel("D_box (360 × 360 grid)")
        ax.set_ylabel("max displacement, blocks in equilibrium (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    ax = axes[-1]
    for alpha in alphas:
        means = []
        failed = []
        for theta in thetas:
            sel = [r for r in rows if r["alpha"] == alpha and r["theta"] == theta]
            d = np.array([r["disp_mm"] for r in sel])
            means.append(np.nanmean(d) if np.isfinite(d).any() else np.nan)
            failed.append(sum(r["n_failed"] for r in sel) / max(len(sel), 1))
        line, = ax.plot(thetas, means, "o-", label=f"α = {alpha:.0f}°")
        for th, m, f in zip(thetas, means, failed):
            ax.annotate(f"{f:.1f}", (th, m), textcoords="offset points", xytext=(4, 4),
                        fontsize=7, color=line.get_color())
    ax.set_title("mean displacement against θ (labels: failed blocks per case)", fontsize=9)
    ax.set_xlabel("θ (°)")
    ax.set_ylabel("mean max displacement (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    print(f"\nwrote {png}")


def main(argv):
    if not argv:
        print(__doc__)
        return 2
    rows = read(Path(argv[0]))
    print_table(group_table(rows))
    trends(rows)
    if "--png" in argv:
        figure(rows, Path(argv[argv.index("--png") + 1]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
