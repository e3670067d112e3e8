"""The run summary, timings and inputs sections of ``report.html`` (:mod:`rockmass.run_report`)."""

from __future__ import annotations

import html
from pathlib import Path
from typing import TYPE_CHECKING

from .html_report import fmt, note, table
from .report_files import _Note

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


def _shown_path(path: str, out: Path) -> str:
    """An input's path as recorded, or relative to the run folder when it lies inside it (an
    earlier stage's output)."""
    try:
        return Path(path).resolve().relative_to(out.resolve()).as_posix()
    except (ValueError, OSError):
        return str(path)


def _sub(title: str, body: str) -> str:
    return f"<h3>{html.escape(title)}</h3>{body}"


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

