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

Catch :class:`FairlineError` to catch them all.
"""


class FairlineError(ValueError):
    """Bad input or options (the CLI's exit status 2); base of all fairline errors."""


class FairlineFileError(FairlineError, OSError):
    """A file could not be opened, read or written."""


class FairlineComputationError(FairlineError, RuntimeError):
    """The computation failed (the CLI's exit status 1)."""


__all__ = ["FairlineError", "FairlineFileError", "FairlineComputationError"]
