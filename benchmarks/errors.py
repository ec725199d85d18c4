"""The one error a command of ``mimo-radar-bench`` reports to its user."""

from __future__ import annotations


class BenchError(ValueError):
    """A run, study or command cannot start (or finish) for a reason its user can fix.

    The message is one line naming the input and what is allowed; the command line prints it as
    ``mimo-radar-bench: error: ...`` and exits with code 2. Everything a command checks before it
    writes anything raises this.
    """
