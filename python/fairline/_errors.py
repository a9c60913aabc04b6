"""Exceptions raised by fairline.

The classes follow the command-line tool's exit status (README "Exit status"):

* :class:`FairlineError` (a :class:`ValueError`): bad input or options, the
  CLI's exit status 2 — a malformed file, a non-manifold mesh, an index out
  of range, a NaN coordinate, an unknown option value. The message is the
  one the CLI prints after ``error:``.
* :class:`FairlineFileError` (also an :class:`OSError`): a file could not be
  opened, read or written by the operating system (missing file, no
  permission).
* :class:`FairlineComputationError` (also a :class:`RuntimeError`): the
  computation failed (a solver broke down), the CLI's exit status 1.
* :class:`FairlineNotConvergedError` (a :class:`FairlineComputationError`):
  a method with a stopping rule of its own (``smooth(method=
  "schneider-kobbelt")``) stopped without meeting it; carries
  ``stop_reason``, the ``report`` and the positions ``V`` it reached.
* :class:`FairlineTypeError` (also a :class:`TypeError`): an argument of
  the wrong type.

Every error the package raises is a :class:`FairlineError`; catch it to
catch them all (Ctrl-C still raises :class:`KeyboardInterrupt`).
"""


class FairlineError(ValueError):
    """Bad input or options (the CLI's exit status 2); base of all fairline errors."""


class FairlineFileError(FairlineError, OSError):
    """A file could not be opened, read or written."""


class FairlineComputationError(FairlineError, RuntimeError):
    """The computation failed (the CLI's exit status 1)."""


class FairlineTypeError(FairlineError, TypeError):
    """An argument of the wrong type."""


class FairlineNotConvergedError(FairlineComputationError):
    """The method stopped without meeting its stopping rule (the CLI exits 1
    with the same sentence). ``stop_reason`` is the report's
    ``"stop_reason"`` (``"stagnated"``, ``"diverged"``, ``"no_descent"``,
    ``"work_limit"``, ``"max_iterations"``), ``report`` the whole report and
    ``V`` the positions reached (for inspection only)."""

    def __init__(self, message: str, *, stop_reason: str, report: dict, V=None) -> None:
        super().__init__(message)
        self.stop_reason = stop_reason
        self.report = report
        self.V = V


__all__ = [
    "FairlineError",
    "FairlineFileError",
    "FairlineComputationError",
    "FairlineNotConvergedError",
    "FairlineTypeError",
]
