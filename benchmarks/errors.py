"""The one error a command of ``mimo-radar-bench`` reports to its user."""

from __future__ import annotations

import re


class BenchError(ValueError):
    """A run, study or command cannot start (or finish) for a reason its user can fix.

    The message is one line naming the input and what is allowed; the command line prints it as
    ``mimo-radar-bench: error: ...`` and exits with code 2. Everything a command checks before it
    writes anything raises this.
    """


#: The command line's flag for each argument of the harness's functions that its errors name.
FLAGS = {
    "trials": "--trials",
    "steps": "--steps",
    "seed": "--seed",
    "shard_size": "--shard-size",
    "agent_params": "--agent-param",
    "workers": "--workers",
    "threads": "--threads",
    "backend": "--backend",
    "max_hours": "--max-hours",
    "device": "--device",
    "device_mode": "--device-mode",
    "out": "--out",
    "timesteps": "--timesteps",
    "seeds": "--seeds",
}


class HarnessError(BenchError):
    """A run the harness refuses, in the words of its Python API.

    The message marks the arguments it names in backticks (```trials` must be ...``):
    ``str()`` gives them as the Python names (``trials must be ...``), and
    :meth:`for_command_line` as the command line's flags (``--trials must be ...``).
    """

    def for_command_line(self) -> str:
        return re.sub(r"`(\w+)`", lambda m: FLAGS.get(m.group(1), m.group(1)), self.args[0])

    def __str__(self) -> str:
        return re.sub(r"`(\w+)`", r"\1", self.args[0])
