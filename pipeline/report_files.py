"""Files of a run folder as ``report.html`` shows them (:mod:`rockmass.run_report`).

:class:`_Note` is the one failure of the report: a file a section needs is missing or unreadable,
and its message is shown in the section's place. The helpers here name a file relative to the run
folder (:func:`_rel`), embed a stage's image (:func:`_image`), and read the trace-map statistics
that several sections share (:func:`_stage_statistics`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from .html_report import figure, file_data_uri, note

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


class _Note(Exception):
    """A file the section needs is missing or unreadable; the message is shown in its place."""


def _rel(path: Path, out: Path) -> str:
    try:
        return str(path.relative_to(out))
    except ValueError:
        return path.name


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

