"""The output folder of a subcommand: created on demand, and never left behind empty by a failure.

Subcommands compute everything first and write at the end (each file atomically, see
:mod:`rockmass.atomic`). :func:`output_folder` wraps that last step: it creates the folder, and if
writing fails it removes the folder again when the failure left it empty, then reports the failure
as a :class:`~rockmass.errors.RunError` naming the folder (exit code 1: the input was fine, the
output could not be written).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

from .errors import RunError

__all__ = ["output_folder", "print_json", "print_summary", "csv_text"]


@contextlib.contextmanager
def output_folder(path) -> Iterator[Path]:
    """Context manager yielding the output folder ``path`` (created with its parents)."""
    folder = Path(path)
    existed = folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        yield folder
    except OSError as exc:
        if not existed:
            with contextlib.suppress(OSError):
                folder.rmdir()  # only succeeds when nothing was left in it
        where = exc.filename or folder
        raise RunError(f"{where}: cannot write the outputs: {exc.strerror or exc}") from exc


def print_json(document) -> None:
    """Write a JSON document to stdout (``--json``): strict JSON, no NaN, indented."""
    import json
    import sys

    json.dump(document, sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


def print_summary(document, as_json: bool, text) -> None:
    """Print a subcommand's result: the JSON document with ``--json``, else ``text(document)``."""
    if as_json:
        print_json(document)
    else:
        print(text(document))


def csv_text(columns: dict) -> str:
    """CSV of equal-length columns (name -> values): numbers with 17 significant digits (``inf`` as
    ``inf``), booleans as 0/1, strings quoted if needed. The one CSV table writer of the commands."""
    import csv
    import io

    import numpy as np

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names = list(columns)
    w.writerow(names)
    cols = [np.asarray(columns[n]) for n in names]
    n = len(cols[0]) if cols else 0

    def fmt(v):
        if isinstance(v, (bool, np.bool_)):
            return int(v)
        if isinstance(v, (float, np.floating)):
            return repr(float(v))
        if isinstance(v, (np.integer,)):
            return int(v)
        return v

    for i in range(n):
        w.writerow([fmt(c[i]) for c in cols])
    return buf.getvalue()
