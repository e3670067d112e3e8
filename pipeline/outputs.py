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

__all__ = ["output_folder", "print_json", "print_summary"]


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
