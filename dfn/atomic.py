"""Atomic file replacement: the one public implementation every rockmass writer uses (docs/design.md §3.7).

Public API: :func:`atomic_open` (a file handle) and :func:`atomic_path` (a temporary name, for
writers that take a path: ``savefig``, ``meshio.write``). Each replaces one file.

A writer never opens its destination. It writes a temporary file in the destination's folder (the
same file system, so the final rename is atomic on POSIX and on Windows), fsyncs it, and renames it
over the destination with :func:`os.replace`; the folder is then fsynced (best effort) so the rename
itself survives a crash. If anything fails before the rename, ``KeyboardInterrupt`` included, the
temporary file is removed and the destination keeps its previous content (or stays absent), so a
killed or failed write never leaves a truncated file that looks complete.

Temporary names start with ``.tmp-`` and end with the destination's full name
(``.tmp-3f9c…-overlay.png``): hidden on POSIX, easy to recognise, and keeping every suffix, so writers
that choose the format from the suffix work through :func:`atomic_path`.

Permissions are those the file would have had if written in place: a new file gets ``0o666`` filtered
by the umask (the temporary file is created with that mode, not the ``0o600`` of
:func:`tempfile.mkstemp`), and a replaced file keeps its permission bits.

Where it lives and who uses it. ``rockmass.dfn`` is the base layer of the dependency direction
(docs/design.md §1): imaging, blockgen and solver build on it and the pipeline imports every stage, so
each of them imports this module as ``from rockmass.dfn.atomic import atomic_open, atomic_path``.
``rockmass.fractal`` imports nothing of ours: its one writer, the box-count plot, saves to the path
it is given, and its caller (``rockmass boxcount``) gives it a temporary name from
:func:`atomic_path`. The pipeline's :mod:`rockmass.atomic` is the layer above, for a command's
outputs: it creates the target's folder and adds bytes, text and strict-JSON entry points, all
through this module (no second copy of the mechanics). The module imports only the standard
library, and importing it does not load numpy or shapely (``rockmass.dfn`` loads its public names
lazily).
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import IO

__all__ = ["atomic_open", "atomic_path", "destination_name"]

_TMP_PREFIX = ".tmp-"
_TOKEN_BYTES = 8
#: A temporary name of this module: the prefix, the random token in hex, ``-``, the destination's name.
_TMP_NAME = re.compile(re.escape(_TMP_PREFIX) + f"[0-9a-f]{{{2 * _TOKEN_BYTES}}}-(.+)", re.DOTALL)
_MODES = ("w", "wb")
_CREATE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)


def _tmp_name(target: Path) -> Path:
    """A fresh temporary name beside ``target`` that ends with the target's full name."""
    return target.with_name(f"{_TMP_PREFIX}{secrets.token_hex(_TOKEN_BYTES)}-{target.name}")


def destination_name(name: str) -> str | None:
    """The name of the file a temporary file of this module becomes, or None if ``name`` is not a
    temporary name of this module (a killed writer leaves such files behind: debris).

    Examples
    --------
    >>> destination_name(".tmp-0123456789abcdef-overlay.png"), destination_name(".tmp-notes")
    ('overlay.png', None)
    """
    match = _TMP_NAME.fullmatch(name)
    return None if match is None else match.group(1)


def _create_tmp(target: Path) -> tuple[Path, int]:
    """Create a new temporary file beside ``target`` (``O_EXCL``, mode ``0o666`` less the umask)."""
    while True:
        tmp = _tmp_name(target)
        try:
            return tmp, os.open(tmp, _CREATE_FLAGS, 0o666)
        except FileExistsError:  # 64 random bits collided: draw again (never touch the other file)
            continue


def _fsync_folder(folder: Path) -> None:
    """Persist the rename itself (best effort: not every platform can open a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def _replacing(tmp: Path, target: Path) -> Iterator[None]:
    """Rename ``tmp`` onto ``target`` when the block succeeds; remove ``tmp`` if anything fails.

    A replaced ``target`` lends its permission bits to the new file, as writing it in place would.
    """
    try:
        yield
        try:
            mode = stat.S_IMODE(os.stat(target).st_mode)
        except OSError:  # nothing to replace: the new file keeps the mode it was created with
            mode = None
        if mode is not None:
            with contextlib.suppress(OSError):  # best effort: some file systems cannot chmod
                os.chmod(tmp, mode)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_folder(target.parent)


@contextlib.contextmanager
def atomic_open(
    path: str | os.PathLike[str], mode: str = "w", *, encoding: str | None = None, newline: str | None = None
) -> Iterator[IO]:
    """Context manager yielding a file handle whose content replaces ``path`` on success.

    Parameters
    ----------
    path : str or path-like
        Destination file; its folder must exist.
    mode : {"w", "wb"}, default "w"
        Text or binary writing.
    encoding : str, optional
        Text encoding; default None, meaning UTF-8 (never the locale's). Not allowed with ``"wb"``.
    newline : str, optional
        As for :func:`open` (use ``""`` for the :mod:`csv` module). Default None.

    Yields
    ------
    file object
        Open for writing; it is flushed, fsynced and closed before the rename.

    Raises
    ------
    ValueError
        If ``mode`` is not ``"w"`` or ``"wb"``, or ``encoding`` / ``newline`` is given with ``"wb"``.
    OSError
        If the folder is missing or not writable, or the rename fails; the temporary file is
        removed and a previous file at ``path`` is left as it was.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_open(folder / "a.txt") as handle:
    ...     _ = handle.write("done")
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('done', ['a.txt'])
    """
    if mode not in _MODES:
        raise ValueError(f"mode must be one of {list(_MODES)}, got {mode!r}")
    if mode == "wb" and (encoding is not None or newline is not None):
        raise ValueError("encoding and newline apply to text mode 'w' only, not to 'wb'")
    if mode == "w" and encoding is None:
        encoding = "utf-8"
    target = Path(path)
    tmp, fd = _create_tmp(target)
    with _replacing(tmp, target), open(fd, mode, encoding=encoding, newline=newline) as handle:
        yield handle
        handle.flush()
        os.fsync(handle.fileno())


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Context manager yielding a temporary path, beside ``path``, that is renamed onto it on success.

    For writers that want a file name rather than a handle (``savefig``, ``meshio.write``). The block
    must create the file; on success it is fsynced and renamed onto ``path``.

    Parameters
    ----------
    path : str or path-like
        Destination file; its folder must exist.

    Yields
    ------
    pathlib.Path
        Where the block writes: a name beside ``path`` that ends with its full name (so its suffix is
        ``path``'s) and does not exist yet.

    Raises
    ------
    FileNotFoundError
        If the block left nothing at the temporary name; ``path`` is not touched.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_path(folder / "mesh.vtu") as tmp:
    ...     _ = tmp.write_text("<VTKFile/>")
    ...     print(tmp.name.startswith(".tmp-"), tmp.suffix)
    True .vtu
    >>> [p.name for p in folder.iterdir()]
    ['mesh.vtu']
    """
    target = Path(path)
    tmp = _tmp_name(target)
    with _replacing(tmp, target):
        yield tmp
        if not os.path.lexists(tmp):
            raise FileNotFoundError(
                f"nothing was written for {target}: the block did not create the temporary file {tmp}"
            )
        if tmp.is_file():
            fd = os.open(tmp, os.O_RDONLY)
            try:
                with contextlib.suppress(OSError):  # fsync on a read-only handle fails on Windows
                    os.fsync(fd)
            finally:
                os.close(fd)
