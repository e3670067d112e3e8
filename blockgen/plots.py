"""``blocks.png``: blocks coloured by region, contacts coloured by joint set, potential cracks in
grey, excavation outlines."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .model import CONTACT_KINDS, KIND_GLUED, SOURCE_CRACK, BlockModel

__all__ = ["plot_blocks"]


def plot_blocks(model: BlockModel, path, title: str | None = None, dpi: int = 150) -> Path:
    """Draw ``model`` to ``path`` (PNG, written atomically). Block edges take the colour of the
    joint set of the block's longest joint contact; potential cracks (glued, source -3) are drawn
    over them as thin grey lines."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    from rockmass.dfn.atomic import atomic_path

    from .blockio import _block_sets

    polys = [model.polygon(i) for i in range(model.n_blocks)]
    region_colours = plt.get_cmap("Pastel1")(np.arange(max(1, len(model.region_names))) % 9)
    set_colours = plt.get_cmap("tab10")(np.arange(10))
    face = region_colours[model.region]
    face[model.region > 0, 3] = 0.35  # excavated blocks drawn faintly
    sets = _block_sets(model)
    edge = np.where(sets[:, None] >= 0, set_colours[sets % 10], (0.3, 0.3, 0.3, 1.0))
    fig, ax = plt.subplots(figsize=(8, 8 * np.ptp(model.domain_xy_m[:, 1])
                                    / max(np.ptp(model.domain_xy_m[:, 0]), 1e-300)))
    try:
        ax.add_collection(PolyCollection(polys, facecolors=face, edgecolors=edge,
                                         linewidths=0.3 if model.n_blocks > 2000 else 0.6))
        _draw_cracks(ax, model)
        d = np.vstack([model.domain_xy_m, model.domain_xy_m[:1]])
        ax.plot(d[:, 0], d[:, 1], color="k", lw=1.0)
        for k in range(1, len(model.region_names)):
            import shapely

            mask = model.region == k
            if mask.any():
                outline = shapely.union_all([shapely.Polygon(p) for p, m in zip(polys, mask) if m])
                for g in shapely.get_parts(outline):
                    xy = np.asarray(g.exterior.coords)
                    ax.plot(xy[:, 0], xy[:, 1], color="crimson", lw=1.2,
                            label=model.region_names[k])
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        counts = ", ".join(f"{name}: {int((model.contact_kind == i).sum())}"
                           for i, name in enumerate(CONTACT_KINDS))
        ax.set_title(title or f"{model.n_blocks} blocks; contacts {counts}", fontsize=8)
        if len(model.region_names) > 1:
            ax.legend(fontsize=7, loc="upper right")
        with atomic_path(Path(path)) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
    finally:
        plt.close(fig)
    return Path(path)


def _draw_cracks(ax, model: BlockModel) -> None:
    """Potential-crack contacts as grey lines (the common boundary of the two blocks)."""
    crack = (model.contact_kind == KIND_GLUED) & (model.contact_source == SOURCE_CRACK)
    if not crack.any():
        return
    import shapely
    from matplotlib.collections import LineCollection

    polys = model.to_shapely()
    a, b = model.contact_blocks[crack].T
    common = shapely.intersection(shapely.boundary(polys[a]), shapely.boundary(polys[b]))
    coords, index = shapely.get_coordinates(shapely.get_parts(common), return_index=True)
    same = index[1:] == index[:-1]
    segs = np.stack([coords[:-1][same], coords[1:][same]], axis=1)
    ax.add_collection(LineCollection(segs, colors=(0.35, 0.35, 0.35, 1.0),
                                     linewidths=0.25 if len(segs) > 2000 else 0.4))
