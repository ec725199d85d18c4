"""numba, when installed (the ``fast`` extra): the compiled twins of the hot paths use it, and
every one of them has a numpy path that runs without it."""

import os
from collections.abc import Iterable
from typing import Any

try:  # pragma: no cover - exercised when numba is installed
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    HAVE_NUMBA = False


def uncached(kernels: Iterable[Any]) -> list[str]:
    """The names of the numba kernels (dispatchers) whose on-disk cache does not exist yet: their
    first call compiles them. A kernel whose cache cannot be told (another numba) counts as
    cached, so this never claims a compilation it cannot see."""
    names = []
    for kernel in kernels:
        try:
            index = kernel._cache._cache_file._index_path
        except AttributeError:
            continue
        if not os.path.exists(index):
            names.append(kernel.__name__)
    return names


__all__ = ["HAVE_NUMBA", "numba", "uncached"]
