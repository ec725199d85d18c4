"""numba, when installed (the ``fast`` extra): the compiled twins of the hot paths use it, and
every one of them has a numpy path that runs without it."""

try:  # pragma: no cover - exercised when numba is installed
    import numba

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    numba = None
    HAVE_NUMBA = False

__all__ = ["HAVE_NUMBA", "numba"]
