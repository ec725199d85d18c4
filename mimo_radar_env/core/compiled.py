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
import types
from collections.abc import Callable, Iterable, Iterator
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

    def for_batch(self, name: str, batch: int) -> Any:
        """Kernel ``name`` for a batch of ``batch`` trials: its threaded twin ``name + "_threaded"``
        (:func:`twins`, where the module names one) when there are threads to spread over and
        more than one chunk of trials to spread, else ``name``."""
        threaded = f"{name}_threaded"
        if threaded in self.kernels and batch > CHUNK and threads() > 1:
            return self.get(threaded)
        return self.get(name)

    def module_getattr(self, name: str) -> Any:
        if name in self.kernels and HAVE_NUMBA:
            return self.get(name)
        raise AttributeError(f"module {self.module!r} has no attribute {name!r}")


#: Trials per chunk of a threaded kernel (:func:`twins`): a chunk's trials share one set of
#: scratch arrays (allocated once per chunk, not per trial); the chunks are what ``prange``
#: spreads over numba's threads.
CHUNK = 64


def twins(
    function: Callable[..., Any], names: tuple[str, str] | None = None, **options: Any
) -> tuple[Any, Any]:
    """``function`` compiled twice, serially and with ``parallel=True`` (its ``prange`` over
    chunks of trials spread over numba's threads), under ``names`` (default: its name without
    the leading underscore, and that with ``_threaded``): numba keys its on-disk cache by the
    qualified name, so two dispatchers of one source need two names or each would load the
    other's machine code. Each trial's arithmetic is the same in both, so are the numbers; the
    serial one compiles in about half the time."""
    import numba

    stem = function.__name__.lstrip("_")
    compiled = []
    for name, parallel in zip(names or (stem, f"{stem}_threaded"), (False, True), strict=True):
        twin = types.FunctionType(function.__code__, function.__globals__, name, function.__defaults__)
        twin.__qualname__ = name
        compiled.append(numba.njit(cache=True, parallel=parallel, **options)(twin))
    return compiled[0], compiled[1]


def threads() -> int:
    """The threads a compiled kernel may spread its trials over: numba's thread count (all the
    cores unless set: a harness worker sets its own, :func:`set_threads`)."""
    import numba

    return numba.get_num_threads()


def set_threads(count: int) -> None:
    """Let the compiled kernels use ``count`` threads (numba's ``set_num_threads``)."""
    import numba

    numba.set_num_threads(count)


@contextlib.contextmanager
def with_threads(count: int | None) -> Iterator[None]:
    """The compiled kernels on ``count`` threads while the block runs (None: as they are)."""
    if count is None or not HAVE_NUMBA:
        yield
        return
    before = threads()
    set_threads(count)
    try:
        yield
    finally:
        set_threads(before)


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


def load_cached(kernels: Iterable[Any]) -> None:
    """Load into this process the machine code numba's on-disk cache holds for ``kernels`` (each
    signature cached for this machine and for the kernel's current source), as their first calls
    would (a cached file that cannot be read back is compiled anew, as that call would). Nothing
    runs, so numba starts no threads. Where the cache cannot be read this way (another numba), a
    kernel is left to its first call."""
    for kernel in kernels:
        try:
            cache, codegen = kernel._cache, kernel.targetctx.codegen()
            keys = cache._cache_file._load_index()
            current = [key[0] for key in keys if key == cache._index_key(key[0], codegen)]
        except Exception:  # noqa: BLE001 - numba's private cache API: the first call loads it
            continue
        for signature in current:
            kernel.compile(signature)


__all__ = [
    "CHUNK",
    "HAVE_NUMBA",
    "LazyKernels",
    "load_cached",
    "repair_cache",
    "set_threads",
    "threads",
    "twins",
    "uncached",
    "with_threads",
]
