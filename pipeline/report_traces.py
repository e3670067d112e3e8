"""The trace-map sections of ``report.html`` (:mod:`rockmass.run_report`): trace maps and rose
diagrams, I / Y / X / E topology with the XYI ternary diagram, the trace-length distribution with the
fitted size law, the P21 map, and the box-counting dimension.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import TYPE_CHECKING

from .html_report import figure, fmt, note, png_base64, table
from .report_dfn import _size_text
from .report_files import _image, _Note, _stage_statistics, _value

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


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
    confident = _confident_table(run) if run.has("extract") else ""
    return "".join(large + small) + confident


#: Which column of the confident-statistics table to read, by detector (docs/imaging.md §7.1:
#: on the real labelled photographs the ridge filter's score-kept traces are far closer to the
#: labels than all its traces; the learned detector's filters have already removed most doubtful
#: traces, and its score-kept set is the smaller, more conservative one).
_CONFIDENT_READING = {
    "ridge": "With the ridge filter, on real photographs the second column is the closer to a "
             "geologist's map of the major joints; on clean images whose every faint line is a "
             "joint, the first.",
    "learned": "The learned detector's filters have already left out most doubtful traces: the "
               "second column is the more conservative reading (fewer traces, less trace length), "
               "not a more accurate one.",
}
_CONFIDENT_READING["cnn"] = _CONFIDENT_READING["learned"]  # the learned chain with the network


def _confident_table(run: _Run) -> str:
    """The extracted traces' headline statistics with and without the low-score traces
    (``statistics_confident`` of extract/summary.json, docs/imaging.md §7.1); empty without it."""
    summary = run.json("extract", "summary.json")
    confident = summary.get("statistics_confident") or {}
    every, kept = summary.get("statistics"), confident.get("statistics")
    if not isinstance(every, dict) or not isinstance(kept, dict):
        return ""
    keys = ("Number of Traces", "Areal Frequency P20", "Fracture Intensity P21", "Trace Mean Length",
            "Box-counting Dimension")
    rows = [[key, fmt(_value(every.get(key) or {})), fmt(_value(kept.get(key) or {}))] for key in keys]
    threshold = confident.get("min_joint_score")
    extraction = summary.get("extraction") or {}
    detector = ((extraction.get("detector_choice") or {}).get("kept")  # "auto" kept one of them
                or (extraction.get("params") or {}).get("detector"))
    text = (f"{confident.get('traces_left_out')} of the {_value(every.get('Number of Traces') or {})} "
            f"extracted traces score under {fmt(threshold)}. The per-trace joint score "
            "(docs/imaging.md §7.1) says how likely each is a joint. " + _CONFIDENT_READING.get(
                detector, ""))
    return f"<p>{html.escape(text)}</p>" + table(
        ["extracted traces", "all", f"joint score ≥ {fmt(threshold)}"], rows, "t-confident")


def _trace_stage(run: _Run) -> str:
    """The stage whose trace statistics the topology, length and P21 sections show: ``traces``
    (a run's traces stage analyses extract's traces, or the map of [run] traces), else ``extract``."""
    return "traces" if run.has("traces") else "extract"


def _section_topology(run: _Run) -> str:
    """Node counts I / Y / X / E, the topological parameters, and the XYI ternary diagram."""
    from .dfn.plots import plot_xyi_ternary

    stage = _trace_stage(run)
    stats = _stage_statistics(run, stage)
    counts = stats.get("Node Counts") or {}
    n = {k: counts.get(k) for k in "IYXE"}
    rows = [[k, fmt(v)] for k, v in n.items()]
    for key in ("Number of Branches", "Connections per Trace", "Connections per Branch"):
        rows.append([key, fmt(_value(stats.get(key) or {}))])
    parts = [table(["node / parameter", "value"], rows, "t-nodes")]
    if not all(isinstance(n[k], int) and n[k] >= 0 for k in "IYX") or n["I"] + n["Y"] + n["X"] == 0:
        return "".join(parts) + note(f"{stage}/summary.json has no I, Y or X node: no ternary diagram.")
    fig = plot_xyi_ternary(n["I"], n["Y"], n["X"])
    parts.append(figure(f"XYI ternary diagram of the {stage} stage's node counts (Sanderson & Nixon 2015); "
                        "E nodes (ends censored by the window) are not part of it; dashed: lines of "
                        "constant connections per branch", png_base64(fig), "small"))
    return "".join(parts)


def _size_survival(run: _Run, stage: str, stats: dict):
    """(S(l) callable, legend text, caption text) of the radius laws that ``dfn/fitted.json`` fitted
    to these traces, or (None, None, why not)."""
    from .dfn.size_fit import trace_length_functions
    from .dfn.sizes import ExponentialSize, LognormalSize, PowerLawSize
    from .manifest import local_path

    if not run.has("dfn") or not (run.dirs["dfn"] / "fitted.json").exists():
        return None, None, "no size law was fitted in this run (a dfn stage with [dfn.fit] faces fits one)"
    faces = (((run.json("dfn", "manifest.json").get("config") or {}).get("dfn") or {}).get("fit") or {}).get("faces")
    traced = str((stats.get("input") or {}).get("path", "")) if stage == "traces" else ""
    config_dir = Path(str((run.doc or {}).get("config", "."))).parent  # manifests: config-relative
    paths = {str(local_path(str(f.get("file", "")), config_dir, run.out).resolve())
             for f in faces or [] if isinstance(f, dict)}
    if not traced or str(Path(traced).resolve()) not in paths:
        return None, None, "the dfn stage's size law was not fitted to these traces"
    build = {"power_law": lambda p: PowerLawSize(p["r_min_m"], p["r_max_m"], p["alpha"]),
             "lognormal": lambda p: LognormalSize(p["mean_m"], p["sd_m"]),
             "exponential": lambda p: ExponentialSize(p["scale_m"])}
    laws = [(s["size"]["n_traces"], build[s["size"]["family"]](s["size"]["params"]), s)
            for s in run.json("dfn", "fitted.json").get("sets") or []
            if (s.get("size") or {}).get("ok") and s["size"].get("family") in build and s["size"].get("n_traces")]
    if not laws:
        return None, None, "dfn/fitted.json holds no successful size fit"
    total = sum(n for n, _, _ in laws)

    def survival(l):
        return sum(n * trace_length_functions(size, l)[1] for n, size, _ in laws) / total

    text = "; ".join(f"{s.get('name')}: {_size_text(s['size']['family'], s['size']['params'])}" for _, _, s in laws)
    return (survival, "fitted disk radius laws, trace-length S(l)",
            f"line: the trace-length survival S(l) of the disk radius laws fitted in the dfn stage "
            f"({text}), weighted by each set's traces; that fit corrects for censoring and for the "
            "window's bias toward long traces (Laslett 1982), so the clipped lengths need not follow it")


def _section_lengths(run: _Run) -> str:
    """Complementary cumulative distribution of trace lengths, censoring stated, with the fitted law."""
    from .dfn.plots import plot_trace_lengths

    stage = _trace_stage(run)
    stats = _stage_statistics(run, stage)
    traces = stats.get("traces") or {}
    lengths, censored = traces.get("length") or [], traces.get("censored") or []
    if not lengths or len(lengths) != len(censored):
        return note(f"{stage}/summary.json lists no trace lengths.")
    ends = traces.get("end_class") or []
    both = sum(1 for e in ends if list(e).count("E") == 2)
    one = sum(1 for e in ends if list(e).count("E") == 1)
    try:
        survival, label, fit_text = _size_survival(run, stage, stats)
    except (_Note, KeyError, TypeError, ValueError) as exc:
        survival, label, fit_text = None, None, f"the fitted size law cannot be drawn ({exc})"
    unit = traces.get("unit", "m")
    fig = plot_trace_lengths(lengths, censored, fitted_survival=survival, fitted_label=label or "", unit=unit)
    caption = (f"Trace lengths inside the window ({stage}), complementary cumulative, log-log: "
               f"{len(lengths)} traces, {sum(bool(c) for c in censored)} censored by the window edge "
               f"({one} with one end, {both} with both ends on it; open markers, their lengths are lower "
               f"bounds); {fit_text}")
    return figure(caption, png_base64(fig))


def _section_p21_map(run: _Run) -> str:
    """P21 per cell over the window (the summary's "P21 Map")."""
    from .dfn.plots import plot_p21_map

    stage = _trace_stage(run)
    stats = _stage_statistics(run, stage)
    grid = stats.get("P21 Map")
    if not isinstance(grid, dict) or not grid.get("p21"):
        raise _Note(f"{stage}/summary.json has no P21 map (written by an older rockmass: rerun the stage)")
    unit = grid.get("unit", "m")
    fig = plot_p21_map(grid["p21"], grid["origin_xy"], float(grid["cell_size"]), unit=unit)
    total = sum(sum(row) for row in grid.get("length") or [])
    area = sum(sum(row) for row in grid.get("area") or [])
    caption = (f"P21 on {fmt(grid['cell_size'])} {unit} square cells over the window ({stage}): trace "
               f"length in each cell over the cell's area inside the window; {fmt(total)} {unit} of traces "
               f"on {fmt(area)} {unit}², P21 {fmt(total / area if area else None)} {unit}/{unit}² overall; "
               "blank: outside the window. Cells cut by the window edge have small areas and noisy values")
    return figure(caption, png_base64(fig))


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

