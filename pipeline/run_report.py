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
stereonet                 ``scanline/stereonet.png``, and the pole density contoured from the poles
                          of ``scanline/summary.json`` ("intersections")
scanline spacings, RQD    ``scanline/summary.json``: spacings with their fitted laws, RQD per group
trace topology            node counts I / Y / X / E and the XYI ternary diagram (traces, else extract)
trace lengths             clipped lengths and censoring of the trace summary, with the radius law
                          that ``dfn/fitted.json`` fitted to the same traces
P21 map                   the "P21 Map" of the trace summary
box counting              ``boxcount/boxcount.png`` and ``boxcount.json``; D of traces / extract
intensities               P10 (scanline), P20 / P21 (traces, extract, boxcount, DFN sections), P32 (DFN)
DFN                       ``dfn/fitted.json``, ``dfn/manifest.json`` (config), realization summaries,
                          and the pole density of the first realization's disks (its fractures.csv)
block model               ``blocks/blocks.png``, ``blocks/blocks.json``
solver stages, energy     ``solve/result.json``
displacement map          ``solve/blocks_NNNN.vtu`` of the last frame (drawn here)
plastic zones             the zones of deformable blocks in that frame, by how they yielded
contact slip, opening     ``solve/contacts.vtu`` (plastic slip and opening of the final contacts)
histories                 ``solve/history.csv`` (drawn here) and the monitors of ``result.json``
========================  ==========================================================================

A missing or unreadable file gives a short note in its section, never an exception: the report is
written after the run's outputs and must not make a finished run fail.

This module reads the run folder (:class:`_Run`) and assembles the page in the order of
:data:`SECTIONS`; the sections are drawn by :mod:`~rockmass.report_summary` (run summary, inputs),
:mod:`~rockmass.report_traces` (traces, topology, lengths, P21 map, box counting),
:mod:`~rockmass.report_scanline` (stereonet, spacings and RQD), :mod:`~rockmass.report_intensity`,
:mod:`~rockmass.report_dfn`, :mod:`~rockmass.report_solve` (block model, solver stages, histories,
energy) and :mod:`~rockmass.report_solve_maps` (displacement, plastic zones, contacts), with the
shared file helpers of :mod:`~rockmass.report_files`.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

from .html_report import BASE_CSS, PRINT_CSS, note
from .report_dfn import _orientation_text  # noqa: F401 - tests import it from here
from .report_dfn import _realizations, _section_dfn
from .report_files import _Note, _rel
from .report_intensity import _section_intensities
from .report_scanline import _section_scanline, _section_stereonet
from .report_solve import _section_blocks, _section_energy, _section_histories, _section_solver
from .report_solve_maps import _has_zones, _section_contacts, _section_displacement, _section_plastic
from .report_summary import _section_inputs, _section_run
from .report_traces import (_section_boxcount, _section_lengths, _section_p21_map, _section_topology,
                            _section_traces)
from .run_config import STAGES  # stage folder names, in the order a run runs them

__all__ = ["STAGES", "write_run_report"]


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


def _json(path: Path, out: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise _Note(f"{_rel(path, out)} is missing") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise _Note(f"{_rel(path, out)} is not readable JSON ({exc})") from None


# ----------------------------------------------------------------------------------- the page --


#: (id, title, stages that make the section appear or None for always, section function)
SECTIONS = (
    ("run", "Run summary and timings", None, _section_run),
    ("inputs", "Inputs", None, _section_inputs),
    ("traces", "Traces and rose diagrams", ("extract", "traces"), _section_traces),
    ("topology", "Trace topology: node counts and XYI diagram", ("extract", "traces"), _section_topology),
    ("lengths", "Trace-length distribution", ("extract", "traces"), _section_lengths),
    ("p21map", "P21 map", ("extract", "traces"), _section_p21_map),
    ("stereonet", "Stereonet", ("scanline",), _section_stereonet),
    ("scanline", "Scanline spacings and RQD", ("scanline",), _section_scanline),
    ("boxcount", "Box-counting dimension", ("boxcount",), _section_boxcount),
    ("intensity", "Intensities P10, P20, P21, P32", ("scanline", "extract", "traces", "boxcount", "dfn"),
     _section_intensities),
    ("dfn", "DFN sets", ("dfn",), _section_dfn),
    ("blocks", "Block model", ("blocks",), _section_blocks),
    ("solver", "Solver stages", ("solve",), _section_solver),
    ("displacement", "Displacement map", ("solve",), _section_displacement),
    ("plastic", "Plastic zones", ("solve",), _section_plastic),
    ("contacts", "Contact slip and opening", ("solve",), _section_contacts),
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
