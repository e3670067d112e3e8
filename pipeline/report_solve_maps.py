"""The maps of a solved model in ``report.html`` (:mod:`rockmass.run_report`): displacement of the
blocks at the final frame, plastic zones of deformable blocks, and slip and opening of the contacts.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from .html_report import figure, fmt, note, png_base64, pyplot
from .report_files import _Note, _rel

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


def _frames(run: _Run) -> tuple[Path, Path | None, str | None]:
    """(last frame, first frame of the last DEM stage or None, that stage's name) as .vtu paths;
    from result.json's frame list, else the highest blocks_NNNN.vtu."""
    folder = run.dirs["solve"]
    try:
        frames = [f for f in run.json("solve", "result.json").get("frames") or [] if f.get("file")]
    except (_Note, AttributeError):
        frames = []
    if not frames:
        found = sorted(folder.glob("blocks_[0-9][0-9][0-9][0-9].vtu"))
        if not found:
            raise _Note(f"{_rel(folder, run.out)} holds no blocks_NNNN.vtu frame")
        return found[-1], None, None
    stage = frames[-1].get("stage")
    first = next(f for f in frames if f.get("stage") == stage)
    if first is frames[0] or first is frames[-1]:
        return folder / frames[-1]["file"], None, None
    return folder / frames[-1]["file"], folder / first["file"], stage


def _read_frame(path: Path, out: Path) -> dict[int, tuple]:
    """Block id -> (polygon (k, 2), displacement (2,), active, plastic state) of one .vtu frame
    (plastic state: the zone's bits, docs/dem.md §16; -1 for a rigid block or without zones)."""
    import meshio.vtu  # its reader raises; meshio.read would print and exit on a bad file
    import numpy as np

    try:
        mesh = meshio.vtu.read(str(path))
    except FileNotFoundError:
        raise _Note(f"{_rel(path, out)} is missing") from None
    except Exception as exc:  # noqa: BLE001 - XML, zlib, base64 and meshio errors on a bad file
        raise _Note(f"{_rel(path, out)} is not a readable VTU file "
                    f"({type(exc).__name__}{': ' if str(exc) else ''}{exc})") from None
    blocks, n = {}, 0
    for k, cells in enumerate(mesh.cells):
        data = {key: np.asarray(v[k]) for key, v in mesh.cell_data.items()}
        ids = data.get("block_id", np.arange(n, n + len(cells.data)))
        active = data.get("active", np.ones(len(cells.data)))
        state = data.get("plastic_state", np.full(len(cells.data), -1))
        for c, conn in enumerate(cells.data):
            blocks[int(ids[c])] = (mesh.points[conn, :2], data["displacement"][c, :2],
                                   bool(active[c]), int(state[c]))
        n += len(cells.data)
    return blocks


def _displacement_panel(fig, ax, blocks: dict, values: dict, title: str) -> float:
    """Active blocks coloured by ``values`` (mm), removed blocks dotted; returns the largest value."""
    from matplotlib.collections import PolyCollection

    on = [b for b, (_, _, active, _) in blocks.items() if active]
    coll = PolyCollection([blocks[b][0] for b in on], array=[values[b] for b in on], cmap="viridis",
                          edgecolors="k", linewidths=0.2)
    ax.add_collection(coll)
    off = [blocks[b][0] for b, (_, _, active, _) in blocks.items() if not active]
    if off:
        ax.add_collection(PolyCollection(off, facecolors="none", edgecolors="0.6", linewidths=0.4,
                                         linestyles="dotted"))
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title, fontsize=10)
    fig.colorbar(coll, ax=ax, shrink=0.8, label="displacement (mm)")
    return max((values[b] for b in on), default=0.0)


def _section_displacement(run: _Run) -> str:
    """Blocks at the final frame coloured by displacement magnitude since the model's original
    position and, with several DEM stages, by the displacement during the last stage alone."""
    import math as m

    last, first, stage = _frames(run)
    blocks = _read_frame(last, run.out)
    total = {b: 1e3 * m.hypot(*d) for b, (_, d, _, _) in blocks.items()}
    start = _read_frame(first, run.out) if first is not None else None
    plt = pyplot()
    fig, axes = plt.subplots(1, 2 if start else 1, figsize=(13 if start else 7.5, 5.5), squeeze=False)
    peak = _displacement_panel(fig, axes[0, 0], blocks, total, f"final frame ({last.name}): total")
    caption = (f"Displacement magnitude at the final frame ({last.name}) from the model's original "
               f"position; largest {fmt(peak)} mm")
    if start:
        during = {b: 1e3 * m.hypot(*(d - start[b][1])) if b in start else 0.0
                  for b, (_, d, _, _) in blocks.items()}
        peak_stage = _displacement_panel(fig, axes[0, 1], blocks, during, f"during stage {stage}")
        caption += (f". Right: during the last stage, {stage} ({first.name} to {last.name}); "
                    f"largest {fmt(peak_stage)} mm")
    if any(not active for _, _, active, _ in blocks.values()):
        caption += ". Dotted outlines: removed (excavated) blocks"
    src = png_base64(fig)
    plt.close(fig)
    return figure(caption, src)


#: Colours of the plastic-zone map: never yielded, shear, tension, both (in the past; docs/dem.md
#: §16.3), and rigid blocks.
_PLASTIC_COLOURS = {"elastic": "#f2efe6", "shear": "#d62728", "tension": "#1f77b4",
                    "shear and tension": "#9467bd", "rigid": "#d9d9d9"}


def _plastic_kind(state: int) -> str:
    if state < 0:
        return "rigid"
    shear, tension = bool(state & 4), bool(state & 8)
    return ("shear and tension" if shear and tension else "shear" if shear
            else "tension" if tension else "elastic")


def _has_zones(run: _Run) -> bool:
    """Whether the run's solver had deformable blocks (else the plastic-zone map is left out)."""
    try:
        return bool(run.json("solve", "result.json").get("zones"))
    except (_Note, AttributeError):
        return False


def _section_plastic(run: _Run) -> str:
    """The zones of deformable blocks at the final frame coloured by how they yielded (docs/dem.md
    §16): the seed's plastic-zone map (Jiang et al., Fig. 6b)."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    zones = run.json("solve", "result.json")["zones"]
    last, _first, _stage = _frames(run)
    blocks = _read_frame(last, run.out)
    live = [b for b, (_, _, active, _) in blocks.items() if active]
    kinds = [_plastic_kind(blocks[b][3]) for b in live]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 6))
    ax.add_collection(PolyCollection([blocks[b][0] for b in live],
                                     facecolors=[_PLASTIC_COLOURS[k] for k in kinds],
                                     edgecolors="0.5", linewidths=0.1))
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(handles=[Patch(color=c, label=k) for k, c in _PLASTIC_COLOURS.items()],
              fontsize=8, loc="upper right")
    caption = (f"Zones that yielded by the final frame ({last.name}): "
               f"{fmt(zones.get('plastic_area_m2'))} m² of {zones.get('zones')} zones (shear "
               f"{fmt(zones.get('shear_yield_area_m2'))} m², tension "
               f"{fmt(zones.get('tension_yield_area_m2'))} m²; yielding at the last step "
               f"{fmt(zones.get('plastic_area_now_m2'))} m²); largest plastic strain "
               f"{fmt(zones.get('max_plastic_strain'))}")
    src = png_base64(fig)
    plt.close(fig)
    return figure(caption, src)


def _read_contacts(path: Path, out: Path) -> dict:
    """Point data of ``contacts.vtu`` (solver/vtu.py: one vertex per contact slot) and its points."""
    import meshio.vtu
    import numpy as np

    try:
        mesh = meshio.vtu.read(str(path))
    except FileNotFoundError:
        raise _Note(f"{_rel(path, out)} is missing (written by rockmass solve since issue 19)") from None
    except Exception as exc:  # noqa: BLE001 - XML, zlib, base64 and meshio errors on a bad file
        raise _Note(f"{_rel(path, out)} is not a readable VTU file ({type(exc).__name__}: {exc})") from None
    data = {k: np.asarray(v) for k, v in mesh.point_data.items()}
    need = ("block_a", "block_b", "normal", "length_m", "plastic_slip_m", "opening_m")
    if missing := [k for k in need if k not in data]:
        raise _Note(f"{_rel(path, out)} lacks the point data {', '.join(missing)}")
    return {"xy": np.asarray(mesh.points)[:, :2], **data}


def _section_contacts(run: _Run) -> str:
    """Contacts at the end of the run coloured by accumulated plastic slip and by opening."""
    from .blockgen.plots import contact_segments, draw_contact_values

    c = _read_contacts(run.dirs["solve"] / "contacts.vtu", run.out)
    n = c["xy"].shape[0]
    if n == 0:
        return note("solve/contacts.vtu holds no contact (no block touches another at the end of the run).")
    segments = contact_segments(c["xy"], c["normal"], c["length_m"], c["block_a"], c["block_b"])
    try:
        last, _first, _stage = _frames(run)
        frame = _read_frame(last, run.out)
        polygons = [p for p, _, active, _ in frame.values() if active]
    except _Note:
        polygons = None
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5))
    slip, opening = 1e3 * c["plastic_slip_m"].reshape(-1), 1e3 * c["opening_m"].reshape(-1)
    draw_contact_values(axes[0], segments, slip, polygons=polygons, label="plastic slip (mm)", cmap="magma_r")
    axes[0].set_title("accumulated plastic shear slip", fontsize=10)
    draw_contact_values(axes[1], segments, opening, polygons=polygons, label="opening (mm)", cmap="coolwarm",
                        symmetric=True)
    axes[1].set_title("normal opening (negative: overlap under compression)", fontsize=10)
    src = png_base64(fig)
    plt.close(fig)
    slipping = int((c["plastic_slip_m"] > 0).sum())
    caption = (f"The {n} contact slots at the end of the run (solve/contacts.vtu), each drawn along the "
               f"stretch of joint it stands for: left, plastic shear slip accumulated over the run "
               f"(largest {fmt(float(slip.max()))} mm; {slipping} slots slipped); right, opening at the "
               f"final state (largest gap {fmt(float(opening.max()))} mm, largest overlap "
               f"{fmt(float(-opening.min()))} mm; colour scale logarithmic in |opening| beyond 1/1000 of the "
               "largest)")
    return figure(caption, src)

