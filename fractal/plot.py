"""Plots of a box count: the log-log curve with its fit, and the local slopes.

matplotlib is imported inside the function (Agg backend), so importing the fractal stage stays light.
"""

from __future__ import annotations

import numpy as np

from .boxcount import BoxCount

__all__ = ["plot_box_count"]


def plot_box_count(result: BoxCount, path, title: str | None = None) -> None:
    """Write a two-panel figure of ``result`` to ``path`` (format from the suffix, e.g. PNG).

    Left: log N against log(1/delta) — every size as a point, the sizes in the fit range filled, the
    fitted line over the fit range, and D with its 95 % interval, R^2 and the offset spread in the
    legend. Right: the local slopes against box size, with D as a horizontal line, so a crossover
    shows as a drift or a step.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    sizes = result.sizes_px
    counts = result.fit_counts
    x = 1.0 / sizes
    fit = result.in_fit
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax, ax2 = fig.subplots(1, 2)
    ax.loglog(x[~fit], counts[~fit], "o", mfc="none", color="0.5", label="outside fit range")
    ax.loglog(x[fit], counts[fit], "o", color="C0", label="in fit range")
    xf = x[fit]
    line = np.exp(result.intercept) * xf**result.dimension
    lo, hi = result.ci95
    ax.loglog(xf, line, "-", color="C3",
              label=f"D = {result.dimension:.3f}  (95% CI {lo:.3f}–{hi:.3f})\n"
                    f"R² = {result.r2:.4f}, offsets: {result.offset_range[0]:.3f}–"
                    f"{result.offset_range[1]:.3f}")
    ax.axvspan(xf.min(), xf.max(), color="C0", alpha=0.07, lw=0)
    ax.set_xlabel(f"1 / box size  (box size in pixels of the {result.grid}² grid)")
    ax.set_ylabel("boxes N" + (" (face-corrected)" if result.face_counts is not None else ""))
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(True, which="both", alpha=0.2)
    mid = np.sqrt(sizes[:-1] * sizes[1:])
    ax2.semilogx(mid, result.local_slopes, ".-", color="C0")
    ax2.axhline(result.dimension, color="C3", lw=1)
    ax2.axvspan(sizes[fit].min(), sizes[fit].max(), color="C0", alpha=0.07, lw=0)
    ax2.set_xlabel("box size (pixels)")
    ax2.set_ylabel("local slope  −d log N / d log δ")
    ax2.set_ylim(min(0.0, float(np.min(result.local_slopes))) - 0.1,
                 max(2.2, float(np.max(result.local_slopes))) + 0.1)
    ax2.grid(True, which="both", alpha=0.2)
    fig.suptitle(title or f"box counting ({result.method})", fontsize=10)
    fig.savefig(path, dpi=120)
