"""All-or-nothing output sets: a command's outputs are its previous complete set or its new one,
never a mix (issue 18).

A subcommand computes everything first and writes at the end, inside :func:`output_set`: the files
go into a fresh staging folder, which replaces the set in ``--out`` with renames once every file is
written. A failed write or a kill leaves the previous complete set (or nothing, if there was none);
the next command writing into the same ``--out`` finishes or undoes what a kill interrupted
(:func:`recover_output_set`) and removes the debris. Entries of ``--out`` that the command does not
produce (a user's notes, a photo) stay; the entries it produces, and names it owns (``owns``: the
``blocks_NNNN.vtu`` frames of an earlier solve) are replaced or dropped.

The swap, for a target ``T`` with an existing set (the default):

1. write everything into ``.T.rockmass-partial``, beside ``T``; write the list of the user's
   entries to keep (the journal ``.rockmass-carry.json``) into it; rename it to
   ``.T.rockmass-ready`` (the set is complete);
2. rename ``T`` to ``.T.rockmass-old``, then ``.T.rockmass-ready`` to ``T`` (the new set is in place);
3. move each kept entry from ``.T.rockmass-old`` into ``T``, remove the journal and the old folder.

(Below, ``T.partial``, ``T.ready`` and ``T.old`` stand for these hidden siblings; their names never
match a folder of the user's, such as an ``out.old`` backup.)

Between the two renames of step 2, ``T`` is briefly absent; at no time does it hold a mix.

In place, when ``T`` cannot be renamed (it is a mount point, it holds the working directory, as
``--out .`` does, or its parent folder is not writable): the set is staged in
``T/.rockmass-partial``, renamed to ``T/.rockmass-ready`` once complete, with a journal of the
command's old entries to drop; those move to ``T/.rockmass-old``, the new ones into ``T``, and both
folders are removed. A kill in the middle leaves ``T/.rockmass-ready``, and the next command
finishes the commit from the journal.

A failure during a commit is undone before the error is raised. Two commands writing into the
same ``--out`` at the same time are not supported (the second one's recovery removes the first
one's staging folder). Writing through a symbolic link
inside ``--out`` cannot happen: the staging folder is new, and an owned name that is a link in the
old set is dropped, not followed.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
from collections.abc import Iterable, Iterator
from pathlib import Path

from .dfn.atomic import destination_name
from .errors import RunError

__all__ = ["PARTIAL_SUFFIX", "output_set", "recover_output_set", "remove_entry", "is_write_debris",
           "remove_write_debris", "destination", "write_error"]

#: Suffix of a staging folder; a folder with this name is written into directly (it already is
#: one: ``rockmass run`` stages each stage in ``DIR/<stage>.partial``).
PARTIAL_SUFFIX = ".partial"
_JOURNAL = ".rockmass-carry.json"
#: Staging folders: hidden siblings ``.<name><suffix>`` of the target, or inside it when in place.
_PARTIAL, _READY, _OLD = ".rockmass-partial", ".rockmass-ready", ".rockmass-old"
_INTERNAL = {_JOURNAL, _PARTIAL, _READY, _OLD}


def is_write_debris(name: str) -> bool:
    """True for a temporary file name of :mod:`rockmass.dfn.atomic` left by a killed writer.

    >>> is_write_debris(".tmp-0123456789abcdef-result.json"), is_write_debris(".tmp-notes")
    (True, False)
    """
    return destination_name(name) is not None


def remove_write_debris(folder: Path) -> None:
    """Remove the temporary files a killed writer left in ``folder`` (:func:`is_write_debris`)."""
    for entry in folder.iterdir():
        if is_write_debris(entry.name):
            remove_entry(entry)


def remove_entry(path: Path) -> None:
    """Remove a file, a symbolic link (never what it points to) or a folder tree, if present."""
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        path.unlink()
    elif path.is_dir():
        shutil.rmtree(path)


def _sibling(target: Path, suffix: str) -> Path:
    """The hidden sibling ``.<name>.rockmass-<what>`` of ``target``: named so that no folder of
    the user's (an ``out.old`` backup) is ever taken for one of ours."""
    return target.with_name(f".{target.name}{suffix}")


def _real_dir(path: Path) -> bool:
    return path.is_dir() and not path.is_symlink()


def _clean_names(names) -> list[str]:
    """Entry names from a journal: plain names only (no path can leave the folder)."""
    if not isinstance(names, list):
        return []
    return [n for n in names if isinstance(n, str) and "/" not in n and n not in ("", ".", "..")]


def _journal(folder: Path) -> dict[str, list[str]]:
    """The journal in ``folder`` (``keep``: the user's entries; ``drop`` and ``new``: the command's
    old and new entries), {} when it has none or it is unreadable."""
    try:
        record = json.loads((folder / _JOURNAL).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(record, dict):
        return {}
    return {key: _clean_names(record.get(key)) for key in ("keep", "drop", "new")}


def _write_journal(folder: Path, **names: list[str]) -> None:
    (folder / _JOURNAL).write_text(json.dumps(names), encoding="utf-8")


def _move(source: Path, destination: Path, names: Iterable[str]) -> list[str]:
    """Move the entries ``names`` from ``source`` into ``destination`` (skipping those absent from
    ``source`` or already in ``destination``); return the names moved."""
    moved = []
    for name in names:
        if os.path.lexists(source / name) and not os.path.lexists(destination / name):
            os.replace(source / name, destination / name)
            moved.append(name)
    return moved


def _owned(name: str, new: set[str], owns: tuple[re.Pattern, ...]) -> bool:
    """Whether an entry of the previous set is the command's (replaced or dropped), not the user's."""
    return (name in new or name in _INTERNAL or is_write_debris(name)
            or any(p.fullmatch(name) for p in owns))


# ------------------------------------------------------------------------------------- recovery


def _recover_swap(target: Path) -> None:
    """Finish or undo a swap (module doc, steps 1-3) that a kill interrupted."""
    remove_entry(_sibling(target, _PARTIAL))
    ready, old = _sibling(target, _READY), _sibling(target, _OLD)
    if os.path.lexists(ready):
        if os.path.lexists(target) or ready.is_symlink():
            remove_entry(ready)  # complete, but the swap never started: the previous set stays
        else:
            os.replace(ready, target)  # T absent: the complete new set goes in
    if not os.path.lexists(target) and _real_dir(old):
        os.replace(old, target)  # a kill between the two renames, and no new set: the previous
        remove_entry(target / _JOURNAL)
    if _real_dir(target):
        if _real_dir(old):
            _move(old, target, _journal(target).get("keep", []))
        remove_entry(target / _JOURNAL)
        remove_entry(old)


def _recover_in_place(target: Path) -> None:
    """Finish an in-place commit that a kill interrupted (its staged set is complete), or drop an
    unfinished staging folder."""
    remove_entry(target / _PARTIAL)
    ready, old = target / _READY, target / _OLD
    if _real_dir(ready):
        record = _journal(ready)
        _commit_entries(ready, target, record.get("drop", []), record.get("new", []))
    remove_entry(ready)
    remove_entry(old)


def recover_output_set(target: str | os.PathLike) -> None:
    """Bring ``target`` back to one complete set after a killed :func:`output_set`, and remove debris.

    Swap: ``T.partial`` is an unfinished set (removed); ``T.ready`` with ``T`` present is a finished
    set whose swap never started (removed: the previous set stays); ``T.ready`` with ``T`` absent is
    swapped in; ``T.old`` with ``T`` absent is put back; a journal in ``T`` finishes moving the user's
    entries back from ``T.old``. In place: ``T/.rockmass-ready`` is committed. Temporary files of a
    killed writer (``.tmp-…``) inside ``T`` are removed.
    """
    target = Path(target)
    _recover_swap(target)
    if _real_dir(target):
        _recover_in_place(target)
        remove_write_debris(target)


# ---------------------------------------------------------------------------------- the commits


def _swap(staging: Path, target: Path, owns: tuple[re.Pattern, ...]) -> None:
    """Put the complete set in ``staging`` in place of ``target`` (module doc, steps 1-3)."""
    ready, old = _sibling(target, _READY), _sibling(target, _OLD)
    new = {p.name for p in staging.iterdir()}
    existing = target.is_dir()
    kept = sorted(p.name for p in target.iterdir() if not _owned(p.name, new, owns)) \
        if existing else []
    _write_journal(staging, keep=kept)
    os.replace(staging, ready)
    if not existing:
        os.replace(ready, target)
        remove_entry(target / _JOURNAL)
        return
    os.replace(target, old)
    try:
        os.replace(ready, target)
    except BaseException:
        os.replace(old, target)
        raise
    moved = []
    try:
        for name in kept:
            moved += _move(old, target, [name])
    except BaseException:
        _move(target, old, moved)       # undo: the user's entries back into the previous set,
        os.replace(target, ready)       # the new set out of the way,
        os.replace(old, target)         # the previous set back in place
        raise
    remove_entry(target / _JOURNAL)
    remove_entry(old)


def _commit_entries(ready: Path, target: Path, drop: list[str], new: list[str]) -> None:
    """Move the command's old entries ``drop`` from ``target`` into ``target/.rockmass-old``, then
    the new set's entries ``new`` from ``ready`` into ``target``; undone if a rename fails. Run
    again after a kill, it skips what is done: a new entry no longer in ``ready`` is in place."""
    old = target / _OLD
    old.mkdir(exist_ok=True)
    waiting = [name for name in new if os.path.lexists(ready / name)]
    placed_before = set(new) - set(waiting)
    dropped, placed = [], []
    try:
        for name in drop:
            if name not in placed_before:
                dropped += _move(target, old, [name])
        for name in waiting:
            placed += _move(ready, target, [name])
    except BaseException:
        _move(target, ready, placed)
        _move(old, target, dropped)
        with contextlib.suppress(OSError):
            old.rmdir()  # empty again
        raise
    remove_entry(ready)
    remove_entry(old)


def _commit_in_place(staging: Path, target: Path, owns: tuple[re.Pattern, ...]) -> None:
    """Commit the set staged in ``target/.rockmass-partial`` entry by entry (module doc)."""
    new = sorted(p.name for p in staging.iterdir())
    drop = sorted(p.name for p in target.iterdir()
                  if p.name not in _INTERNAL and _owned(p.name, set(new), owns))
    _write_journal(staging, drop=drop, new=new)
    ready = target / _READY
    os.replace(staging, ready)
    _commit_entries(ready, target, drop, new)


def _in_place(target: Path) -> bool:
    """Whether ``target`` must be committed in place: it exists and cannot be renamed (a mount
    point, the working directory or one of its parents, or a folder whose parent is read-only)."""
    if not _real_dir(target):
        return False
    if os.path.ismount(target) or not os.access(target.parent, os.W_OK | os.X_OK):
        return True
    here, there = Path.cwd().resolve(), target.resolve()
    return here == there or there in here.parents


# -------------------------------------------------------------------------------- the public API


def destination(filename: str | os.PathLike, staging: Path | None = None,
                target: Path | None = None) -> str:
    """The file a user knows for a path a writer failed on: a temporary name (``.tmp-…-name``)
    is shown as the file it becomes, and a path inside ``staging`` as the same path in ``target``.

    >>> destination("out/.tmp-0123456789abcdef-result.json")
    'out/result.json'
    """
    path = Path(os.fsdecode(filename))
    if staging is not None and target is not None:
        try:
            path = target / path.relative_to(staging)
        except ValueError:
            pass
    return str(Path(*(destination_name(part) or part for part in path.parts)))


def write_error(exc: OSError, folder: Path, staging: Path | None = None) -> RunError:
    """:class:`RunError` (exit 1) for a write that failed in the output folder ``folder``, naming
    the file the user asked for (:func:`destination`), never a temporary one."""
    where = destination(exc.filename, staging, folder) if exc.filename else folder
    return RunError(f"{where}: cannot write the outputs: {exc.strerror or exc}")


@contextlib.contextmanager
def _direct(folder: Path) -> Iterator[Path]:
    """Write into ``folder`` as it is (a staging folder already); write errors become RunError."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        yield folder
    except OSError as exc:
        raise write_error(exc, folder) from exc


@contextlib.contextmanager
def output_set(path: str | os.PathLike, owns: Iterable[str] = ()) -> Iterator[Path]:
    """Context manager yielding a fresh folder where a command writes its complete set of outputs,
    which replaces the set in ``path`` when the block succeeds.

    Parameters
    ----------
    path : str or path-like
        The command's ``--out``. Created (with its parents) if missing. If it is a symbolic link,
        the folder it points to is the target. A folder whose name ends with ``.partial`` is
        already a staging folder: it is written into directly.
    owns : iterable of str, default ()
        Regular expressions (full match) of entry names in ``path`` that belong to the command
        besides the ones the new set has (stale ``blocks_\\d{4,}\\.vtu`` frames): they are dropped,
        not kept.

    Yields
    ------
    pathlib.Path
        The folder to write into (``.<name>.rockmass-partial`` beside ``path``, or
        ``<path>/.rockmass-partial`` in place).

    Raises
    ------
    RunError
        When a file cannot be written or the commit fails, naming the file as the user knows it (in
        ``path``, never the temporary name). ``path`` keeps its previous set.
    """
    target = Path(path)
    if target.name.endswith(PARTIAL_SUFFIX):
        with _direct(target) as folder:
            yield folder
        return
    if target.is_symlink() or target.name in ("", ".", ".."):
        target = Path(os.path.realpath(target))
    if os.path.lexists(target) and not target.is_dir():
        raise RunError(f"{target}: cannot write the outputs: it is a file, not a folder")
    patterns = tuple(re.compile(p) for p in owns)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        recover_output_set(target)
        in_place = _in_place(target)
        staging = target / _PARTIAL if in_place else _sibling(target, _PARTIAL)
        staging.mkdir()
    except OSError as exc:
        raise RunError(f"{target}: cannot write the outputs: {exc.strerror or exc}") from exc
    ready = target / _READY if in_place else _sibling(target, _READY)
    try:
        yield staging
        (_commit_in_place if in_place else _swap)(staging, target, patterns)
    except OSError as exc:
        raise write_error(exc, target, staging) from exc
    finally:
        for leftover in (staging, ready):  # nothing, unless the block failed
            with contextlib.suppress(OSError):
                remove_entry(leftover)
