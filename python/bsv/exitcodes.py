"""One rule for the exit status of every ``bsv`` front end (``bsv``, ``bsv bench``, ``bsv process``, ...).

- 0: done.
- 1: the run failed on its input or in the computation (a :class:`bsv.errors.BsvError`; the message says
  what and what to do).
- 2: the call itself must change: an output exists and ``--overwrite`` was not given, a parameter or
  argument is invalid, a benchmark is misconfigured (:class:`~bsv.errors.OutputExistsError`,
  :class:`~bsv.errors.InputError`, :class:`~bsv.errors.BenchError`), or argparse rejected the command line.
- 130: interrupted (Ctrl-C).

:func:`run_command` applies it: every front end's ``main`` wraps its work in it, so a typed error is one
line on stderr, never a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Callable

from .errors import BenchError, BsvError, InputError, OutputExistsError

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


def exit_code(exc: BaseException) -> int:
    """The exit status for an exception that ended a command (see the module's rule)."""
    if isinstance(exc, KeyboardInterrupt):
        return EXIT_INTERRUPTED
    if isinstance(exc, OutputExistsError | InputError | BenchError):
        return EXIT_USAGE
    return EXIT_FAILED


def run_command(prog: str, body: Callable[[], int | None]) -> int:
    """Runs ``body`` and returns its status (``None`` = 0); a BSV error, an existing output or Ctrl-C
    becomes ``prog: error: message`` on stderr and the status of :func:`exit_code`."""
    try:
        return int(body() or 0)
    except KeyboardInterrupt as exc:
        print(f"{prog}: interrupted", file=sys.stderr)
        return exit_code(exc)
    except (BsvError, FileExistsError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return exit_code(exc)


__all__ = ["EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "exit_code", "run_command"]
