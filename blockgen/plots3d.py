"""``keyblocks.png``: the removable blocks around the openings in 3D, coloured by failure mode, with
the tunnel surfaces drawn faintly (docs/blocks.md §9)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_keyblocks", "MODE_COLOURS"]

#: colour of each failure mode drawn (the other modes are not drawn).
MODE_COLOURS = {"fall": "#d62728", "slide": "#ff7f0e", "slide2": "#bcbd22"}


def plot_keyblocks(blocks, keyblocks, path, title: str | None = None, dpi: int = 130) -> Path:
    """Draw the blocks of ``keyblocks`` that can fall or slide (every face of their pieces, coloured
    by mode) and the faces of the excavated pieces on the tunnel walls, to ``path`` (PNG, written
    atomically)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from rockmass.dfn.atomic import atomic_path

    mode_of = {k.block: k.mode for k in keyblocks if k.mode in MODE_COLOURS}
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    walls = [face for p in np.flatnonzero(blocks.excavated)
             for face, j in zip(blocks.pieces[p].faces, blocks.pieces[p].labels)
             if j >= 0 and blocks.planes.label[j] <= -2]
    if walls:
        ax.add_collection3d(Poly3DCollection(walls, facecolor="#cccccc", edgecolor="none", alpha=0.15))
    for mode, colour in MODE_COLOURS.items():
        faces = [face for p in np.flatnonzero(np.isin(blocks.block_id, [b for b, m in mode_of.items()
                                                                           if m == mode]))
                 for face in blocks.pieces[p].faces]
        if faces:
            ax.add_collection3d(Poly3DCollection(faces, facecolor=colour, edgecolor="k",
                                                 linewidth=0.2, alpha=0.85))
    lo, hi = blocks.box_m
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
           xlabel="x (East), m", ylabel="y (North), m", zlabel="z (up), m")
    ax.set_box_aspect(hi - lo)
    counts = {m: sum(1 for v in mode_of.values() if v == m) for m in MODE_COLOURS}
    ax.legend(handles=[Patch(color=c, label=f"{m} ({counts[m]})") for m, c in MODE_COLOURS.items()],
              loc="upper left", fontsize=8)
    ax.set_title(title or f"keyblocks: {len(mode_of)} of {len(keyblocks)} blocks on the openings can move")
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    plt.close(fig)
    return path
