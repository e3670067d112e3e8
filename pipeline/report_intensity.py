"""The intensities section of ``report.html`` (:mod:`rockmass.run_report`): P10, P20, P21 and P32
from whichever stages provide them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .html_report import fmt, note, table
from .report_files import _Note, _stage_statistics, _value

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


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

