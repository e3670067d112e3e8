"""The ``rockmass`` command line: subcommands, exit codes and error reporting.

Exit codes (docs/design.md §4): 0 success; 2 bad input or configuration (the message names the file, the
field and what was expected) — every ``ValueError``, which is what input validation raises, and
input files that cannot be read, which the subcommands re-raise as :class:`InputError`; 1 failure
while running — outputs that cannot be written (:class:`RunError`), and anything unexpected. Heavy modules (numpy, numba, matplotlib,
OpenCV, scikit-image) are imported inside each subcommand's handler, never at start-up, so
``rockmass --help`` is instant and a typo costs nothing.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from .errors import EXIT_BAD_INPUT, EXIT_FAILURE, RunError

__all__ = ["build_parser", "main"]

# The module of every subcommand; each has ``add_parser(subparsers)``, which registers ``run(args)
# -> int`` as the handler. They are imported when the parser is built: keep them light at import.
_SUBCOMMANDS = ("extract_cmd", "score_cmd", "traces_cmd", "boxcount_cmd", "scanline_cmd", "dfn_cmd", "blocks_cmd",
               "blocks3d_cmd", "solve_cmd", "run_cmd", "study_cmd", "warmup")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    from importlib import import_module

    from . import __version__

    parser = argparse.ArgumentParser(
        prog="rockmass",
        description="Jointed rock masses from face photographs and scanlines: traces, fractal "
                    "dimension, DFN, block models and a distinct element solver.")
    parser.add_argument("--version", action="version", version=f"rockmass {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the full traceback of a failure")
    sub = parser.add_subparsers(dest="command", metavar="SUBCOMMAND", required=True)
    for module_name in _SUBCOMMANDS:
        import_module(f".{module_name}", __package__).add_parser(sub)
    return parser


def _refuse_unknown(parser: argparse.ArgumentParser, command: str, extras: list[str]) -> None:
    """Exit 2 with the subcommand's usage, naming the arguments it does not know and, for a
    misspelt option, the closest option it has (``--m-per-pix``: did you mean ``--m-per-px``?)."""
    import difflib

    subcommands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    sub = subcommands.choices[command]
    options = [o for action in sub._actions for o in action.option_strings]
    hints = []
    for extra in extras:
        name = extra.split("=", 1)[0]
        close = difflib.get_close_matches(name, options, n=1, cutoff=0.6) if name.startswith("-") else []
        if close:
            hints.append(f"{name}: did you mean {close[0]}?")
    sub.error(f"unrecognized arguments: {' '.join(extras)}" + "".join(f"; {h}" for h in hints))


def _error(command: str, kind: str, exc: BaseException) -> None:
    print(f"rockmass {command}: {kind}: {exc}", file=sys.stderr)


def _plain_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A library warning (e.g. the solver's zones too coarse for a stage's waves) as one
    ``rockmass: warning: ...`` line, without Python's file and source line; a warning that is not
    a plain ``UserWarning`` (numpy's ``RuntimeWarning``, ...) keeps its category's name."""
    from .inputs import warn

    kind = "" if category is UserWarning else f"{category.__name__}: "
    warn(f"{kind}{message}")


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit code (the console script passes it to ``sys.exit``).

    Without ``argv`` (the console script, ``python -m rockmass``) the process ends when this
    returns: the objects alive then are frozen out of the garbage collector (:func:`gc.freeze`),
    which spares the interpreter its last collections over them on the way out (many objects,
    once numba, scipy and matplotlib are loaded). Every output is written and closed before;
    ``atexit`` handlers, the finalizers of objects freed by reference counting and the flushing
    of stdout and stderr still run; only cyclic garbage left at exit is not collected. Such a process also runs OpenBLAS on
    one thread unless ``OPENBLAS_NUM_THREADS`` says otherwise.
    """
    if argv is None:
        # one BLAS thread: rockmass runs its own threads (the two detectors of `extract`, numba),
        # and OpenBLAS's spin-waiting threads beside them slow the learned detector's matrix
        # products down, badly on a busy machine (docs/imaging.md §3.3). Numpy is not imported
        # yet; a value the user set is kept.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    code = _main(argv)
    if argv is None:
        import gc

        gc.freeze()
    return code


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    args, extras = parser.parse_known_args(argv)  # usage errors exit with code 2 (argparse's rule)
    if extras:
        _refuse_unknown(parser, args.command, extras)
    args.argv = ["rockmass", *(sys.argv[1:] if argv is None else argv)]  # for manifests
    out = getattr(args, "out", None)
    if out and os.path.lexists(out) and not os.path.isdir(out):  # bad input, found before any work
        _error(args.command, "error", f"{out}: --out names an existing file, not a folder; give a "
                                      "folder (created if missing) or move the file away")
        return EXIT_BAD_INPUT
    from .kernel_cache import ensure_writable_cache

    ensure_writable_cache()  # a read-only install without a writable user cache: numba's cache in /tmp
    try:
        with warnings.catch_warnings():  # restores Python's own form when the command ends
            if not args.debug:
                warnings.showwarning = _plain_warning
            return int(args.handler(args) or 0)
    except RunError as exc:  # a failure while running, e.g. outputs that could not be written
        if args.debug:
            raise
        _error(args.command, "failed", exc)
        return EXIT_FAILURE
    except ValueError as exc:  # bad input: InputError, ConfigError and the stages' validation
        if args.debug:
            raise
        _error(args.command, "error", exc)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        _error(args.command, "interrupted", "stopped by the user; no partial output was written")
        return 130
    except MemoryError:  # its message is empty: say what happened
        if args.debug:
            raise
        _error(args.command, "failed", "out of memory: the input or the settings need more memory "
                                       "than this machine has; use a smaller input or settings "
                                       "(run with --debug for the traceback)")
        return EXIT_FAILURE
    except Exception as exc:  # noqa: BLE001 - the CLI's last line of defence maps to exit 1
        if args.debug:
            raise
        _error(args.command, "failed", f"{type(exc).__name__}: {exc} (run with --debug for the "
                                       "traceback)")
        return EXIT_FAILURE
