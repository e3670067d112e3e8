"""``report.html`` of ``rockmass run``: one self-contained page for a run folder.

``rockmass run CONFIG --out DIR`` writes each stage's files into ``DIR/<stage>/`` (exactly what the
single-stage subcommand writes into its ``--out``), then ``DIR/run.json`` (config, its hash, the
rockmass version and, per stage, status ``ran`` / ``reused``, hash, wall time and outputs), then
calls :func:`write_run_report`. The page (no script, no network, every image embedded as a base64
``data:`` URI, readable when printed) has one section per topic, shown only when the stage that
feeds it is in the folder:

========================  ==========================================================================
section                   from
========================  ==========================================================================
run summary, timings      ``run.json``
inputs                    each stage's ``manifest.json`` (paths, SHA-256, sizes)
traces                    ``extract/overlay.png``, ``extract/rose.png``, ``traces/traces.png``,
                          ``traces/rose.png``
stereonet                 ``scanline/stereonet.png``
box counting              ``boxcount/boxcount.png`` and ``boxcount.json``; D of traces / extract
intensities               P10 (scanline), P20 / P21 (traces, extract, boxcount, DFN sections), P32 (DFN)
DFN                       ``dfn/fitted.json``, ``dfn/manifest.json`` (config), realization summaries
block model               ``blocks/blocks.png``, ``blocks/blocks.json``
solver stages, energy     ``solve/result.json``
displacement map          ``solve/blocks_NNNN.vtu`` of the last frame (drawn here)
plastic zones             the zones of deformable blocks in that frame, by how they yielded
histories                 ``solve/history.csv`` (drawn here) and the monitors of ``result.json``
========================  ==========================================================================

A missing or unreadable file gives a short note in its section, never an exception: the report is
written after the run's outputs and must not make a finished run fail.
"""

from __future__ import annotations

import csv
import html
import json
import math
from pathlib import Path

from .html_report import (BASE_CSS, PRINT_CSS, figure, file_data_uri, fmt, note, png_base64, pyplot,
                          table)
from .run_config import STAGES  # stage folder names, in the order a run runs them

__all__ = ["STAGES", "write_run_report"]


class _Note(Exception):
    """A file the section needs is missing or unreadable; the message is shown in its place."""


class _Run:
    """The run folder: ``run.json`` (or ``None`` and a note) and the stage folders it lists — stage
    folders that earlier runs left in DIR are not part of this run and are not shown; without a
    readable run.json, every stage folder present. Each JSON file is parsed once per report
    (:meth:`read`), the DFN realizations listed once (:meth:`realizations`)."""

    def __init__(self, out: Path):
        self.out, self.doc, self.note = out, None, None
        self._parsed: dict[Path, object] = {}
        self._realizations = None
        try:
            doc = self.read(out / "run.json")
            if not isinstance(doc, dict) or not isinstance(doc.get("stages", []), list):
                raise _Note("run.json is not a run record (an object with a list of stages)")
            self.doc = doc
        except _Note as exc:
            self.note = str(exc)
        if self.doc is None:
            named = {n: out / n for n in STAGES}
        else:
            named = {e.get("name"): out / str(e["dir"]) for e in self.stage_entries() if e.get("dir")}
        self.dirs: dict[str, Path] = {n: d for n in STAGES if (d := named.get(n)) and d.is_dir()}

    def stage_entries(self) -> list[dict]:
        return [e for e in (self.doc or {}).get("stages", []) if isinstance(e, dict)]

    def has(self, *names: str) -> bool:
        return any(n in self.dirs for n in names)

    def read(self, path: Path):
        """The parsed JSON file ``path`` (parsed on first use, then the same object; the report only
        reads it), or :class:`_Note` when it is missing or unreadable (every time)."""
        if path not in self._parsed:
            try:
                self._parsed[path] = _json(path, self.out)
            except _Note as exc:
                self._parsed[path] = exc
        value = self._parsed[path]
        if isinstance(value, _Note):
            raise _Note(str(value))
        return value

    def json(self, stage: str, name: str):
        """The parsed ``<stage>/<name>`` (see :meth:`read`)."""
        return self.read(self.dirs[stage] / name)

    def realizations(self) -> tuple[list[tuple[int, dict]], list[str]]:
        """:func:`_realizations` of this run, found and read once."""
        if self._realizations is None:
            try:
                self._realizations = _realizations(self)
            except _Note as exc:
                self._realizations = exc
        if isinstance(self._realizations, _Note):
            raise _Note(str(self._realizations))
        return self._realizations


# ------------------------------------------------------------------------------------ helpers --


def _rel(path: Path, out: Path) -> str:
    try:
        return str(path.relative_to(out))
    except ValueError:
        return path.name


def _shown_path(path: str, out: Path) -> str:
    """An input's path as recorded, or relative to the run folder when it lies inside it (an
    earlier stage's output)."""
    try:
        return Path(path).resolve().relative_to(out.resolve()).as_posix()
    except (ValueError, OSError):
        return str(path)


def _json(path: Path, out: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise _Note(f"{_rel(path, out)} is missing") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise _Note(f"{_rel(path, out)} is not readable JSON ({exc})") from None


def _image(run: _Run, stage: str, name: str, caption: str, cls: str | None = None) -> str:
    """An image of a stage folder as a figure (``cls="small"``: half width, side by side), or a
    note when it is missing or broken."""
    path = run.dirs[stage] / name
    try:
        return figure(caption, file_data_uri(path), cls)
    except FileNotFoundError:
        return note(f"{_rel(path, run.out)} is missing.")
    except (OSError, ValueError) as exc:
        return note(f"{_rel(path, run.out)} cannot be shown ({exc}).")


def _value(entry):
    """The number of a summary entry: ``{"value": x, "unit": u}`` or a plain number."""
    return entry.get("value") if isinstance(entry, dict) else entry


def _stage_statistics(run: _Run, stage: str) -> dict:
    """Trace-map statistics of ``traces`` (summary.json) or ``extract`` (summary.json "statistics")."""
    doc = run.json(stage, "summary.json")
    stats = doc.get("statistics") if stage == "extract" else doc
    if not isinstance(stats, dict):
        raise _Note(f"{stage}/summary.json has no trace statistics (no trace was found)")
    return stats


def _no_negative_zero(v):
    return v + 0.0 if isinstance(v, float) else v  # -0.0 + 0.0 is 0.0: a ledger shows "0", not "-0"


def _sub(title: str, body: str) -> str:
    return f"<h3>{html.escape(title)}</h3>{body}"


# ----------------------------------------------------------------------------------- sections --


def _section_run(run: _Run) -> str:
    """Config, hash, version, and per stage: status, wall time, outputs (the timings table)."""
    if run.doc is None:
        found = ", ".join(run.dirs) or "none"
        return note(f"{run.note}; stage folders found: {found}.")
    d = run.doc
    rows = [["config", str(d.get("config", ""))], ["config hash", str(d.get("config_hash", ""))],
            ["rockmass version", str(d.get("rockmass_version", ""))],
            ["total wall time (s)", fmt(d.get("total_wall_s"))]]
    info = table(["item", "value"], rows, "t-run")
    stages = [[str(e.get("name", "")), str(e.get("status", "")), fmt(e.get("wall_s")),
               str(len(e.get("outputs") or [])), str(e.get("hash", ""))[:12]]
              for e in run.stage_entries()]
    timings = table(["stage", "status", "wall time (s)", "outputs", "hash"], stages, "t-timings")
    return info + _sub("Stages and timings (reused: unchanged inputs and settings, not rerun)", timings)


def _section_inputs(run: _Run) -> str:
    """Input files of every stage (from its manifest.json): path, SHA-256, size."""
    rows, notes = [], []
    for stage in run.dirs:
        try:
            manifest = run.json(stage, "manifest.json")
        except _Note as exc:
            notes.append(note(f"{exc}."))
            continue
        for item in manifest.get("inputs") or []:
            if isinstance(item, dict):
                rows.append([stage, _shown_path(item.get("path", ""), run.out),
                             str(item.get("sha256", ""))[:16], fmt(item.get("bytes"))])
    return (table(["stage", "file", "SHA-256 (first 16)", "bytes"], rows, "t-inputs") if rows
            else note("No input file recorded.")) + "".join(notes)


def _section_traces(run: _Run) -> str:
    """Trace overlay on the photo and trace map by set, then the rose diagrams side by side."""
    large, small = [], []
    if run.has("extract"):
        large.append(_image(run, "extract", "overlay.png", "Extracted traces over the photograph, by set"))
        small.append(_image(run, "extract", "rose.png", "Rose diagram of the extracted traces "
                                                        "(length-weighted)", "small"))
    if run.has("traces"):
        large.append(_image(run, "traces", "traces.png", "Digitised trace map, by set"))
        small.append(_image(run, "traces", "rose.png", "Rose diagram of the trace map (length-weighted)",
                            "small"))
    return "".join(large + small)


def _section_stereonet(run: _Run) -> str:
    """Poles of the scanline survey with the fitted sets."""
    return _image(run, "scanline", "stereonet.png",
                  "Poles to joints of the scanline (lower hemisphere, equal area), by set", "small")


def _section_boxcount(run: _Run) -> str:
    """Box-count plot and D ± 95 % interval, R² (also the D of traces / extract, when present)."""
    rows, notes = [], []

    def add(source, d, ci, r2, fit_range, grid, method):
        ci = ci if isinstance(ci, list) and len(ci) == 2 else [None, None]
        rows.append([source, fmt(d), fmt(ci[0]), fmt(ci[1]), fmt(r2),
                     "–".join(fmt(v) for v in fit_range or []), fmt(grid), fmt(method)])

    doc = None
    try:
        doc = run.json("boxcount", "boxcount.json")
        add("boxcount", doc.get("dimension"), doc.get("ci95"), doc.get("r2"), doc.get("fit_range_px"),
            doc.get("grid"), doc.get("method"))
    except _Note as exc:
        notes.append(note(f"{exc}."))
    for stage in ("traces", "extract"):
        if run.has(stage):
            try:
                e = _stage_statistics(run, stage).get("Box-counting Dimension") or {}
                add(stage, e.get("value"), e.get("ci95"), e.get("r2"), e.get("fit_range_px"),
                    e.get("grid"), e.get("method"))
            except _Note as exc:
                notes.append(note(f"{exc}."))
    caption = "Box counting: number of occupied boxes against box size, with the fitted line"
    if doc is not None and isinstance(doc.get("dimension"), (int, float)):
        lo, hi = (doc.get("ci95") or [None, None])[:2]
        caption += (f"; D = {fmt(doc['dimension'])} (95 % interval {fmt(lo)}–{fmt(hi)}), "
                    f"R² = {fmt(doc.get('r2'))}")
    head = ["source", "D", "95 % CI low", "95 % CI high", "R²", "fit range (px)", "grid", "method"]
    return (_image(run, "boxcount", "boxcount.png", caption) + table(head, rows, "t-boxcount")
            + "".join(notes))


def _intensity_rows_scanline(run: _Run) -> list[list[str]]:
    doc = run.json("scanline", "summary.json")
    rows = []
    for label, entry in [("all", doc.get("all") or {})] + [(f"set {s.get('set')}", s)
                                                          for s in doc.get("sets") or []]:
        rows.append(["P10", fmt(entry.get("p10_per_m")), "1/m", f"scanline, {label}"])
        rows.append(["P10 (Terzaghi)", fmt(entry.get("p10_terzaghi_per_m")), "1/m", f"scanline, {label}"])
    return rows


def _intensity_rows_traces(run: _Run, stage: str) -> list[list[str]]:
    stats = _stage_statistics(run, stage)
    window = stats.get("window") or {}
    area = ((stats.get("input") or {}).get("area") or {}).get("text") or {
        "trace_map": "the map's window polygon", "argument": "a given polygon",
        "bounding_box": "the traces' bounding box", "convex_hull": "the traces' convex hull",
    }.get(window.get("source"), "")
    # issue 19: the area P20 and P21 are per unit of is named, whatever it is
    rows = [["area", fmt(_value(stats.get("Area") or {})), str((stats.get("Area") or {}).get("unit", "")),
             f"{stage}: {area}"]]
    for measure, key in (("P20", "Areal Frequency P20"), ("P21", "Fracture Intensity P21"),
                         ("P21 (Mauldon)", "Fracture Intensity (Mauldon)")):
        entry = stats.get(key) or {}
        rows.append([measure, fmt(_value(entry)), str(entry.get("unit", "")), f"{stage}, all"])
    return rows


def _intensity_rows_boxcount(run: _Run) -> list[list[str]]:
    doc = run.json("boxcount", "boxcount.json")
    if doc.get("p21_per_m") is None:
        return []
    return [["P21", fmt(doc["p21_per_m"]), "m/m²", "boxcount, counted window"]]


def _intensity_rows_dfn(run: _Run) -> list[list[str]]:
    rows = []
    for i, summary in run.realizations()[0]:  # the DFN section notes unreadable ones
        total = summary.get("total") or {}
        rows.append(["P32 target", fmt(total.get("target_p32")), "m²/m³", f"dfn, realization {i}"])
        rows.append(["P32 achieved", fmt(total.get("achieved_p32")), "m²/m³", f"dfn, realization {i}"])
        for sec in summary.get("sections") or []:
            where = f"dfn, realization {i}, section {sec.get('name')}"
            rows.append(["P21", fmt(sec.get("p21")), "m/m²", where])
            rows.append(["P21 expected (P32/C23)", fmt(sec.get("p21_expected")), "m/m²", where])
    return rows


def _section_intensities(run: _Run) -> str:
    """P10 / P20 / P21 / P32 from whatever stages provide them."""
    rows, notes = [], []
    readers = [("scanline", _intensity_rows_scanline),
               ("extract", lambda r: _intensity_rows_traces(r, "extract")),
               ("traces", lambda r: _intensity_rows_traces(r, "traces")),
               ("boxcount", _intensity_rows_boxcount), ("dfn", _intensity_rows_dfn)]
    for stage, reader in readers:
        if run.has(stage):
            try:
                rows += reader(run)
            except _Note as exc:
                notes.append(note(f"{exc}."))
    return (table(["measure", "value", "unit", "source"], rows, "t-intensity") if rows
            else note("No intensity available.")) + "".join(notes)


def _realizations(run: _Run) -> tuple[list[tuple[int, dict]], list[str]]:
    """(index, summary.json) of every ``dfn/realization_NNNN`` folder, in order, and the notes of
    those whose summary cannot be read."""
    out, notes = [], []
    folders = [f for f in sorted(run.dirs["dfn"].glob("realization_*"))
               if f.is_dir() and f.name[12:].isdigit()]
    if not folders:
        raise _Note(f"{_rel(run.dirs['dfn'], run.out)} holds no realization_NNNN folder")
    for folder in folders:
        try:
            out.append((int(folder.name[12:]), run.read(folder / "summary.json")))
        except _Note as exc:
            notes.append(f"{exc}.")
    return out, notes


def _set_laws(run: _Run) -> dict[str, tuple[str, str, str]]:
    """Set name -> (source, orientation text, size-law text), from fitted.json then the config."""
    laws = {}
    try:
        config = (run.json("dfn", "manifest.json").get("config") or {}).get("dfn") or {}
    except _Note:
        config = {}
    for s in config.get("sets") or []:
        o, size = s.get("orientation") or {}, dict(s.get("size") or {})
        law = _size_text(size.pop("distribution", ""), size)
        laws[s.get("name")] = ("config", _orientation_text(o), law)
    if (run.dirs["dfn"] / "fitted.json").exists():
        for s in run.json("dfn", "fitted.json").get("sets") or []:
            size = s.get("size") or {}
            law = (_size_text(size.get("family", ""), size.get("params") or {}) if size.get("ok", True)
                   else f"none ({size.get('reason', '')})")
            laws[s.get("name")] = ("fitted", _orientation_text(s.get("orientation") or {}), law)
    return laws


def _orientation_text(o: dict) -> str:
    from .dfn.orientation import dip_text

    # dip/dip direction as the command line prints them (issue 19: the report said 69/29)
    text = f"{o.get('distribution', '')} {dip_text(o.get('dip_deg'), o.get('dip_direction_deg'))}"
    return text + (f", κ {fmt(o.get('kappa'), 3)}" if o.get("kappa") is not None else "")


def _size_text(family: str, params: dict) -> str:
    return f"{family} " + ", ".join(f"{k} {fmt(v, 4)}" for k, v in params.items())


def _section_dfn(run: _Run) -> str:
    """Per set: orientation and size law (fitted or given), P32 target and achieved per realization."""
    realizations, notes = run.realizations()
    try:
        laws = _set_laws(run)
        law_note = ""
    except _Note as exc:
        laws, law_note = {}, note(f"{exc}.")
    rows = []
    for i, summary in realizations:
        for s in summary.get("sets") or []:
            source, orient, size = laws.get(s.get("name"), ("", "", ""))
            rows.append([str(i), str(s.get("name", s.get("set"))), source, orient, size,
                         fmt(s.get("target_p32")), fmt(s.get("achieved_p32")), fmt(s.get("count"))])
    head = ["realization", "set", "from", "orientation (dip/dip dir.)", "size law (radius)",
            "P32 target (m²/m³)", "P32 achieved (m²/m³)", "disks"]
    return (table(head, rows, "t-dfn") + _dfn_validation(run, [i for i, _ in realizations]) + law_note
            + "".join(note(n) for n in notes))


def _dfn_validation(run: _Run, indices: list[int]) -> str:
    """One line per realization re-sampled with the field geometry (validation.json, with
    ``[dfn.fit] validate = true``): how many measured quantities it reproduces within tolerance."""
    lines = []
    for i in indices:
        path = run.dirs["dfn"] / f"realization_{i:04d}" / "validation.json"
        if not path.exists():
            continue
        try:
            rows = run.read(path).get("rows") or []
            ok = sum(1 for r in rows if r.get("ok"))
            lines.append(f"realization {i}: {ok} of {len(rows)} field measures within tolerance")
        except (_Note, AttributeError) as exc:
            lines.append(f"realization {i}: {exc}")
    if not lines:
        return ""
    return f'<p id="dfn-validation">Validation against the field data: {html.escape("; ".join(lines))}.</p>'



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
    for m in monitors:
        ax.plot(t, [1e3 * math.hypot(x, y) for x, y in zip(h[f"{m}_ux_m"], h[f"{m}_uy_m"])], label=m)
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
                    + "; dashed lines: stage boundaries", src)]
    try:
        mons = run.json("solve", "result.json").get("monitors") or {}
        rows = [[name, fmt(m.get("block")), fmt(m.get("final_ux_m")), fmt(m.get("final_uy_m")),
                 fmt(m.get("final_displacement_m")), fmt(m.get("max_contact_plastic_slip_m"))]
                for name, m in mons.items()]
        if rows:
            parts.append(table(["monitor", "block", "final ux (m)", "final uy (m)", "final |u| (m)",
                                "max plastic slip on its contacts (m)"], rows, "t-monitors"))
    except _Note as exc:
        parts.append(note(f"{exc}."))
    return "".join(parts)


#: (id, title, stages that make the section appear or None for always, section function)
SECTIONS = (
    ("run", "Run summary and timings", None, _section_run),
    ("inputs", "Inputs", None, _section_inputs),
    ("traces", "Traces and rose diagrams", ("extract", "traces"), _section_traces),
    ("stereonet", "Stereonet", ("scanline",), _section_stereonet),
    ("boxcount", "Box-counting dimension", ("boxcount",), _section_boxcount),
    ("intensity", "Intensities P10, P20, P21, P32", ("scanline", "extract", "traces", "boxcount", "dfn"),
     _section_intensities),
    ("dfn", "DFN sets", ("dfn",), _section_dfn),
    ("blocks", "Block model", ("blocks",), _section_blocks),
    ("solver", "Solver stages", ("solve",), _section_solver),
    ("displacement", "Displacement map", ("solve",), _section_displacement),
    ("plastic", "Plastic zones", ("solve",), _section_plastic),
    ("histories", "Monitored histories", ("solve",), _section_histories),
    ("energy", "Energy ledger", ("solve",), _section_energy),
)


def _render(run: _Run, sid: str, title: str, fn) -> str:
    try:
        body = fn(run)
    except _Note as exc:
        body = note(f"{exc}.")
    except Exception as exc:  # noqa: BLE001 - one bad file must not cost the whole report
        body = note(f"This section could not be drawn: {type(exc).__name__}: {exc}.")
    return f'<section id="sec-{sid}"><h2>{html.escape(title)}</h2>{body}</section>\n'


def write_run_report(out_dir: str | Path) -> Path:
    """Write ``out_dir/report.html`` (atomically) from ``run.json`` and the stage folders.

    Parameters
    ----------
    out_dir : str or path-like
        The ``--out`` folder of ``rockmass run``.

    Returns
    -------
    pathlib.Path
        The report's path.
    """
    from .atomic import atomic_write_text

    out = Path(out_dir)
    run = _Run(out)
    shown = [(sid, title, fn) for sid, title, stages, fn in SECTIONS
             if (stages is None or run.has(*stages)) and (sid != "plastic" or _has_zones(run))]
    nav = " · ".join(f'<a href="#sec-{sid}">{html.escape(title)}</a>' for sid, title, _ in shown)
    body = "".join(_render(run, sid, title, fn) for sid, title, fn in shown)
    config = (run.doc or {}).get("config", "")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>rockmass run report</title>
<style>
{BASE_CSS}td:first-child {{ text-align: left; }}
figure img {{ max-width: min(100%, 880px); }}
figure.small {{ display: inline-block; vertical-align: top; width: 440px; margin-right: 1em; }}
.note {{ color: #7a4a00; background: #fff6e0; padding: 4px 8px; font-size: 13px; }}
nav {{ font-size: 13px; margin-bottom: 1em; }}
{PRINT_CSS}</style></head><body>
<h1>rockmass run</h1>
<p>Config: <code>{html.escape(str(config))}</code>; stages in this folder:
{html.escape(", ".join(run.dirs) or "none")}.</p>
<nav>{nav}</nav>
{body}</body></html>
"""
    return atomic_write_text(out / "report.html", page)
