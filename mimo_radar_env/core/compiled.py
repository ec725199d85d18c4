"""numba, when installed (the ``fast`` extra): the compiled twins of the hot paths use it, and
every one of them has a numpy path that runs without it.

numba is imported the first time a compiled twin is needed (``compiled.numba`` is then the
module, or ``None`` without it), not when the package is imported: ``HAVE_NUMBA`` only asks
whether it is installed, so the command line's help and its argument errors answer without it.
"""

import contextlib
import importlib
import importlib.util
import os
import sys
from collections.abc import Iterable
from typing import Any

HAVE_NUMBA = importlib.util.find_spec("numba") is not None


def __getattr__(name: str) -> Any:
    if name == "numba":
        if not HAVE_NUMBA:  # pragma: no cover
            return None
        import numba

        return numba
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class LazyKernels:
    """A module's compiled kernels, imported the first time one is asked for.

    ``LazyKernels(__name__, _update_numba="._average_kernels:update")``: :meth:`get` gives the
    kernel (importing its module, and numba, once, then keeping it as the module's attribute, so
    that an attribute set on the module, a test's stand-in say, is what runs), and
    :meth:`module_getattr` is the module's ``__getattr__``, so ``module._update_numba`` works
    from outside as a plain attribute did.
    """

    def __init__(self, module: str, **kernels: str) -> None:
        self.module, self.kernels = module, kernels

    def get(self, name: str) -> Any:
        namespace = sys.modules[self.module].__dict__
        if name not in namespace:
            where, _, attribute = self.kernels[name].partition(":")
            package = self.module.rpartition(".")[0]
            kernel = getattr(importlib.import_module(where, package), attribute)
            repair_cache(kernel)  # a damaged cache is compiled anew, not a failure of every call
            namespace[name] = kernel
        return namespace[name]

    def module_getattr(self, name: str) -> Any:
        if name in self.kernels and HAVE_NUMBA:
            return self.get(name)
        raise AttributeError(f"module {self.module!r} has no attribute {name!r}")


def repair_cache(kernel: Any) -> bool:
    """Whether ``kernel``'s on-disk cache index was damaged (numba could not read it back: every
    call would fail in numba's ``_load_index``) and was removed, so that its next call compiles
    it anew. A kernel whose cache cannot be told (another numba) is left alone."""
    try:
        cache_file = kernel._cache._cache_file
        load, index = cache_file._load_index, cache_file._index_path
    except AttributeError:
        return False
    try:
        load()
        return False
    except Exception:  # noqa: BLE001 - any failure to read the index back is a damaged index
        with contextlib.suppress(OSError):
            os.remove(index)
        return True


def uncached(kernels: Iterable[Any]) -> list[str]:
    """The names of the numba kernels (dispatchers) whose on-disk cache does not exist yet, or was
    damaged and is removed (:func:`repair_cache`): their first call compiles them. A kernel whose
    cache cannot be told (another numba) counts as cached, so this never claims a compilation it
    cannot see."""
    names = []
    for kernel in kernels:
        try:
            index = kernel._cache._cache_file._index_path
        except AttributeError:
            continue
        if repair_cache(kernel) or not os.path.exists(index):
            names.append(kernel.__name__)
    return names


__all__ = ["HAVE_NUMBA", "LazyKernels", "repair_cache", "uncached"]
