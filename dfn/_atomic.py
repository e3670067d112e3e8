"""Atomic text-file writes for the trace writers (DESIGN.md §3: outputs are written atomically).

A writer never opens its destination. It writes a temporary file in the destination's folder (the
same file system, so the final rename is atomic on POSIX and on Windows), flushes and fsyncs it,
gives it the permissions a normally created file would have, and renames it over the destination
with :func:`os.replace`. If anything fails before the rename, the temporary file is removed and the
destination keeps its previous content (or stays absent), so a killed or failed write never leaves a
truncated file that looks complete.

The pipeline package has a helper of its own, but ``rockmass.dfn`` cannot import it (the dependency
arrow points from ``rockmass`` to the stages), hence this small private copy.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

__all__ = ["atomic_text_writer"]


def _umask() -> int:
    """The process umask, read without changing it where the platform allows (Linux /proc)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)  # fallback: set and restore (briefly visible to other threads)
    os.umask(mask)
    return mask


def _final_mode(path: Path) -> int:
    """Keep an existing destination's permissions; otherwise those of a new file (0o666 & ~umask)."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return 0o666 & ~_umask()


@contextlib.contextmanager
def atomic_text_writer(path: str | os.PathLike[str], *, newline: str | None = None) -> Iterator[IO[str]]:
    """Context manager yielding a UTF-8 text handle whose content replaces ``path`` on success.

    Parameters
    ----------
    path : str or path-like
        Destination file; its folder must exist.
    newline : str, optional
        Passed to :func:`open` (use ``""`` for the :mod:`csv` module). Default None.

    Raises
    ------
    OSError
        If the folder is missing or not writable, or the rename fails; the temporary file is removed.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_text_writer(folder / "a.txt") as handle:
    ...     _ = handle.write("done")
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('done', ['a.txt'])
    """
    path = Path(path)
    handle = tempfile.NamedTemporaryFile(
        "w",
        encoding="utf-8",
        newline=newline,
        dir=path.parent,
        prefix=f".{path.name}.",
        suffix=".tmp",
        delete=False,
    )
    try:
        with handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(handle.name, _final_mode(path))
        os.replace(handle.name, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(handle.name)
        raise
    _fsync_folder(path.parent)


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
