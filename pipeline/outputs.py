"""The output folder of a subcommand and what it prints.

:func:`output_set` (from :mod:`rockmass.output_sets`) is where a command writes its set of outputs:
all of it replaces the previous set, or nothing changes (issue 18). :func:`output_folder` is the
plain variant for outputs that grow while a command runs (a study's cases, kept on resume): it
creates the folder and maps write errors. :func:`refuse_links` keeps a command's writes inside
``--out``.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Iterator
from pathlib import Path

from .errors import InputError
from .output_sets import (PARTIAL_SUFFIX, is_write_debris, output_set, recover_output_set,
                          remove_entry, remove_write_debris, write_error)

__all__ = ["PARTIAL_SUFFIX", "output_folder", "output_set", "recover_output_set", "remove_entry",
           "refuse_links", "is_write_debris", "remove_write_debris", "print_json", "print_summary", "csv_text", "plot_text"]


def refuse_links(out: str | os.PathLike, names: Iterable[str]) -> None:
    """Refuse (:class:`InputError`, exit 2) when an entry that a command writes into inside ``out``
    is a symbolic link: outputs never leave ``out`` through a link (issue 18).

    Parameters
    ----------
    out : str or path-like
        The command's ``--out`` (itself may be a link: the user chose it).
    names : iterable of str
        Relative paths inside ``out`` the command writes into, parents before children
        (``cases``, ``cases/3f2a…``).
    """
    for name in names:
        path = Path(out) / name
        if path.is_symlink():
            raise InputError(f"{path}: is a symbolic link; rockmass writes only inside --out and "
                             "does not follow links there: remove the link or choose another --out")


@contextlib.contextmanager
def output_folder(path) -> Iterator[Path]:
    """Context manager yielding the output folder ``path`` (created with its parents), for outputs
    written one by one as a command runs; write errors become a :class:`RunError` naming the file,
    and a folder the failure left empty is removed again."""
    folder = Path(path)
    existed = folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        yield folder
    except OSError as exc:
        if not existed:
            with contextlib.suppress(OSError):
                folder.rmdir()  # only succeeds when nothing was left in it
        raise write_error(exc, folder) from exc


def plot_text(text: str) -> str:
    """``text`` (a file name) shown as written in a plot title: matplotlib reads ``$…$`` as math,
    and a name such as ``a$\\frac{$b.csv`` made the plot, and the command, fail (issue 18).

    >>> print(plot_text("face$1.geojson"))
    face\\$1.geojson
    """
    return text.replace("$", r"\$")


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
