"""Exceptions that the command-line interface maps to exit codes (docs/design.md §4).

Exit code 2 means bad input or configuration: the message names the file, the field and what was
expected. Exit code 1 means a failure while running. Stage packages (``fractal``, ``dfn``, ...) do not
import this module (the dependency arrow points from ``rockmass`` to the stages): they raise
``ValueError`` / ``TypeError`` for bad arguments and ``OSError`` for unreadable files, and the CLI maps
those to exit code 2 as well.
"""

from __future__ import annotations

__all__ = ["InputError", "ConfigError", "RunError", "EXIT_OK", "EXIT_FAILURE", "EXIT_BAD_INPUT"]

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
