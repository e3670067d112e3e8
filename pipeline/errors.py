"""Exceptions that the command-line interface maps to exit codes (docs/design.md §4).

Exit code 2 means bad input or configuration: the message names the file, the field and what was
expected. Exit code 1 means a failure while running. Stage packages (``fractal``, ``dfn``, ...) do not
import this module (the dependency arrow points from ``rockmass`` to the stages): they raise
``ValueError`` / ``TypeError`` for bad arguments and ``OSError`` for unreadable files, and the CLI maps
those to exit code 2 as well.
"""

from __future__ import annotations

import contextlib
import csv
import os
import re
import functools
from collections.abc import Callable, Iterator

__all__ = ["InputError", "ConfigError", "RunError", "EXIT_OK", "EXIT_FAILURE", "EXIT_BAD_INPUT",
           "reading", "reads", "data_error_text"]

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2


class InputError(ValueError):
    """Bad input data or arguments; the CLI exits with code 2."""


class ConfigError(InputError):
    """A configuration file failed validation.

    Parameters
    ----------
    path : str
        The configuration file.
    problems : list of (field, message)
        Each offending field as a dotted key path (``fractal.grid``, ``dfn.sets[1].kappa``) with what
        was wrong and what is expected.
    """

    def __init__(self, path: str, problems: list[tuple[str, str]]):
        self.path = str(path)
        self.problems = list(problems)
        lines = [f"{self.path}: {field}: {message}" for field, message in self.problems]
        super().__init__("\n".join(lines))


class RunError(RuntimeError):
    """A failure while running (a diverging solver, a fit that cannot be made); exit code 1."""


#: Exceptions of other libraries that the content of a file raises (matched by module and name, so
#: that neither library is imported to recognise them): OpenCV on an image it cannot process,
#: shapely/GEOS on geometry it cannot handle.
_FOREIGN_DATA_ERRORS = {("cv2", "error"), ("shapely.errors", "GEOSException"),
                        ("shapely.errors", "ShapelyError")}


def _foreign(exc: BaseException) -> bool:
    return any((t.__module__, t.__name__) in _FOREIGN_DATA_ERRORS for t in type(exc).__mro__)


def data_error_text(exc: BaseException) -> str | None:
    """What a file's content did, for an exception that bad data raises while it is read or
    processed; None for any other exception (an internal failure).

    >>> data_error_text(RecursionError("maximum recursion depth exceeded"))
    'nested too deeply to be read (maximum recursion depth exceeded)'
    >>> data_error_text(KeyError("x")) is None
    True
    """
    if isinstance(exc, UnicodeDecodeError):
        return f"not UTF-8 text ({exc.reason} at byte {exc.start}); save the file as UTF-8"
    if isinstance(exc, RecursionError):
        return f"nested too deeply to be read ({exc})"
    if isinstance(exc, OverflowError):
        return f"a number is too large to compute with ({exc}); rescale the values"
    if isinstance(exc, csv.Error):
        return f"not a readable CSV table ({exc})"
    if type(exc).__name__ == "LinAlgError":  # numpy's, a ValueError: degenerate numbers
        return (f"the numbers cannot be fitted ({exc}): values that are not finite, too large or "
                "all the same")
    if _foreign(exc):
        return f"{type(exc).__name__}: {exc}".strip()
    if isinstance(exc, ValueError):
        return str(exc)
    return None


#: A quoted stretch of a message (readers quote what they found in the file).
_QUOTED = re.compile(r"'[^'\n]*'|\"[^\"\n]*\"")
_WORD = re.compile(r"\w{3,}")
_LOOKED_AT = 1 << 24  # bytes of a file searched for quoted words; a larger file: every quote goes


def _file_words(path: str | os.PathLike) -> str | None:
    """The start of the file as text (to look quoted words up in); None if it is too large to
    search (then nothing quoted is shown)."""
    try:
        with open(path, "rb") as handle:
            data = handle.read(_LOOKED_AT + 1)
    except OSError:
        return ""  # unreadable: nothing of it can be in the message
    return None if len(data) > _LOOKED_AT else data.decode("utf-8", "replace")


def _from_file(quoted: str, content: str | None) -> bool:
    """Whether a quoted stretch may show content of the file: a word of it (3+ characters, or
    the whole of a shorter one) occurs in ``content``, or the file could not be searched."""
    if content is None:
        return True
    inner = quoted[1:-1]
    words = _WORD.findall(inner) or [inner]
    return any(word in content for word in words if word)


def _scrubbed(text: str, path: str | os.PathLike) -> str:
    """``text`` naming the file ``path`` by its name only, and without what the readers quoted
    from it (a config can name any file the user can read: its content is not echoed, issue 18);
    quoted words that are not in the file (what was expected) stay."""
    shown = os.fspath(path)
    name = os.path.basename(shown) or shown
    for variant in sorted({shown, os.path.abspath(shown), os.path.realpath(shown)}, key=len,
                          reverse=True):
        text = text.replace(variant, name)
    text = text.removeprefix(f"{name}: ")
    content = _file_words(path)
    hidden = _QUOTED.sub(lambda m: "'…'" if _from_file(m.group(0), content) else m.group(0), text)
    return f"{name}: {hidden}"


def _problem_text(exc: BaseException) -> str | None:
    """:func:`data_error_text`, and unreadable files (``OSError``) and :class:`InputError` too."""
    if isinstance(exc, InputError):
        return str(exc)
    if isinstance(exc, OSError):
        return f"cannot read the file: {exc.strerror or exc}"
    return data_error_text(exc)


@contextlib.contextmanager
def reading(path: str | os.PathLike, field: str | None = None, *,
            config: str | os.PathLike | None = None) -> Iterator[None]:
    """Within the block, an exception that a user's file can raise through its content (or by not
    being readable) is bad input (:class:`InputError`, exit 2) that names the file (and ``field``,
    the flag or config key that gave it); anything else passes through (an internal failure, exit 1).

    Parameters
    ----------
    path : str or path-like
        The file read and processed in the block; named by its path as the user gave it.
    field : str, optional
        The flag or config key that named the file (``--mask``, ``run.scanline``).
    config : str or path-like, optional
        The config file that named ``path`` (at ``field``). Then the message is ``config: field:
        name: problem`` with the file shown by its name only and nothing quoted from its content:
        a config may name any readable file (``../../etc/passwd``), errors never echo it.

    Examples
    --------
    >>> with reading("survey.csv", "--scanline"):
    ...     raise OverflowError("int too large to convert to float")
    Traceback (most recent call last):
    ...
    rockmass.errors.InputError: survey.csv: --scanline: a number is too large to compute with (int too large to convert to float); rescale the values
    >>> import pathlib, tempfile
    >>> secret = pathlib.Path(tempfile.mkdtemp()) / "passwd"
    >>> _ = secret.write_text("root:x:0:0:root:/root:/bin/bash\\n")
    >>> with reading(secret, "run.scanline", config="run.toml"):
    ...     raise ValueError(f"{secret}: line 1, column 'root:x:0:0:root:/root:/bin/bash': "
    ...                      "unknown column; expected 'distance'")
    Traceback (most recent call last):
    ...
    rockmass.errors.InputError: run.toml: run.scanline: passwd: line 1, column '…': unknown column; expected 'distance'
    """
    try:
        yield
    except Exception as exc:  # noqa: BLE001 - classified just below, re-raised otherwise
        if config is not None:
            text = _problem_text(exc)
            if text is None:
                raise
            raise InputError(f"{config}: {field}: {_scrubbed(text, path)}") from exc
        if isinstance(exc, InputError):
            raise
        text = data_error_text(exc)
        if text is None:
            raise
        shown = os.fspath(path)
        if shown in text:
            raise InputError(text) from exc  # already names the file
        where = f"{shown}: {field}" if field else shown
        raise InputError(f"{where}: {text}") from exc


def reads(attribute: str) -> Callable[[Callable], Callable]:
    """Decorator for a stage's ``compute(args, ...)`` that reads and processes the file
    ``args.<attribute>``: the call runs inside :func:`reading` of that file."""
    def decorate(compute: Callable) -> Callable:
        @functools.wraps(compute)
        def wrapped(args, *rest, **kwargs):
            with reading(getattr(args, attribute)):
                return compute(args, *rest, **kwargs)
        return wrapped
    return decorate
