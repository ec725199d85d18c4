"""Optional dependencies, imported on demand with an error that names the extra to install."""

from __future__ import annotations

import importlib
from types import ModuleType

from gymnasium.error import DependencyNotInstalled

#: The install command of each extra (CPU torch first for ``rl``: a bare torch requirement
#: would pull a CUDA build of several GB).
INSTALL = {
    "rl": "pip install torch==2.13.0 && pip install 'mimo-radar-env[rl]'",
    "ray": "pip install 'mimo-radar-env[ray]'",
}


def require(module: str, extra: str, what: str) -> ModuleType:
    """Import ``module``, or raise ``DependencyNotInstalled`` naming ``extra`` and how to install it."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise DependencyNotInstalled(
            f"{what} needs {module}, in the {extra} extra: {INSTALL[extra]}"
        ) from exc
