"""``blocks.png``: blocks coloured by region, contacts coloured by joint set, potential cracks in
grey, excavation outlines; and the contact maps of a solved model (:func:`contact_segments`,
:func:`draw_contact_values`): contacts coloured by a value such as plastic slip or opening."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .model import CONTACT_KINDS, KIND_GLUED, SOURCE_CRACK, BlockModel

__all__ = ["contact_segments", "draw_contact_values", "plot_blocks"]


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
        with atomic_path(Path(path)) as tmp:  # "tight": a wide, flat domain keeps its axis labels
            fig.savefig(tmp, dpi=dpi, format="png", bbox_inches="tight")
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


def contact_segments(points_xy, normals, lengths_m, block_a, block_b) -> np.ndarray:
    """The stretch of joint each contact slot stands for, as segments ``(n, 2, 2)``.

    A slot sits at its contact point and stands for ``length_m`` of contact along the tangent
    t = (−n_y, n_x) (solver/vtu.py). Two slots of one pair of blocks with the same normal are the
    two ends of one edge-to-edge contact: each gets the half of the edge between its point and the
    edge's midpoint. Any other slot gets a segment of its length centred on its point.

    Parameters
    ----------
    points_xy : (n, 2) array_like
        Contact points, m.
    normals : (n, 2) array_like
        Unit normals (only the x and y columns are read).
    lengths_m : (n,) array_like
        Contact length of each slot, m.
    block_a, block_b : (n,) array_like of int
        The two blocks of each slot.

    Examples
    --------
    >>> contact_segments([[0, 0], [2, 0], [5, 5]], [[0, 1], [0, 1], [1, 0]], [1, 1, 2],
    ...                  [0, 0, 1], [1, 1, 2]).tolist()
    [[[0.0, 0.0], [1.0, 0.0]], [[2.0, 0.0], [1.0, 0.0]], [[5.0, 4.0], [5.0, 6.0]]]
    """
    p = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
    nrm = np.asarray(normals, dtype=np.float64).reshape(p.shape[0], -1)[:, :2]
    half = 0.5 * np.asarray(lengths_m, dtype=np.float64).reshape(-1)
    tangent = np.column_stack([-nrm[:, 1], nrm[:, 0]])
    seg = np.stack([p - half[:, None] * tangent, p + half[:, None] * tangent], axis=1)
    groups: dict = {}
    keys = zip(np.asarray(block_a).tolist(), np.asarray(block_b).tolist(), map(tuple, np.round(nrm, 9).tolist()))
    for k, key in enumerate(keys):  # slots of one contact: same blocks, same normal
        groups.setdefault(key, []).append(k)
    for slots in groups.values():
        if len(slots) == 2:
            i, j = slots
            mid = 0.5 * (p[i] + p[j])
            seg[i] = (p[i], mid)
            seg[j] = (p[j], mid)
    return seg


def draw_contact_values(ax, segments, values, *, polygons=None, label: str = "", cmap: str = "viridis",
                        symmetric: bool = False):
    """Draw contact segments coloured by ``values`` on ``ax`` (block outlines in light grey below).

    Parameters
    ----------
    ax : matplotlib Axes
    segments : (n, 2, 2) array_like
        From :func:`contact_segments`.
    values : (n,) array_like
        One value per segment (NaN drawn grey).
    polygons : sequence of (k, 2) arrays, optional
        Block outlines.
    label : str
        Colour-bar label.
    symmetric : bool, default False
        For a signed value such as the opening: a colour scale centred on zero from minus to plus the
        largest |value|, logarithmic in |value| beyond 1e-3 of it and linear inside (matplotlib's
        SymLogNorm), so that overlaps of micrometres and gaps of millimetres both show.

    Returns
    -------
    matplotlib.collections.LineCollection
        The coloured contacts (its array holds ``values``).
    """
    from matplotlib.collections import LineCollection, PolyCollection

    if polygons is not None:
        ax.add_collection(PolyCollection(list(polygons), facecolors="none", edgecolors="0.85", linewidths=0.3))
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    finite = v[np.isfinite(v)]
    from matplotlib import colormaps
    from matplotlib.colors import Normalize, SymLogNorm

    if symmetric:
        top = float(np.abs(finite).max()) if finite.size and np.abs(finite).max() > 0 else 1.0
        norm = SymLogNorm(linthresh=1e-3 * top, vmin=-top, vmax=top)
    else:
        low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        norm = Normalize(low, high) if high > low else Normalize(low - 0.5, high + 0.5)
    coll = LineCollection(np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2), array=v, norm=norm,
                          cmap=colormaps[cmap].with_extremes(bad="0.6"), linewidths=1.6)
    ax.add_collection(coll)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.figure.colorbar(coll, ax=ax, shrink=0.8, label=label)
    return coll
