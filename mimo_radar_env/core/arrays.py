"""The array namespace the batch engine computes with: numpy, or torch on a device.

Each equation of the simulation, the tracker and the bound is written once, in numpy's
spelling, against a namespace ``xp`` taken from its inputs (:func:`namespace`): numpy itself for
numpy arrays, so the numpy path runs exactly the calls it always ran, or a :class:`TorchNamespace`
that gives torch the numpy spellings the engine uses (``swapaxes``, ``concatenate``,
``max(axis=, keepdims=)``, ``linalg.cholesky`` raising ``LinAlgError``...). torch is imported only
when a tensor is met or a device is asked for, so ``device=None`` needs no torch.

The counter-based hash works on 64-bit words: numpy's ``uint64``, and on torch (which has no
shifts on ``uint64``) the same bits in ``int64`` with masked logical shifts (:meth:`shift_right`);
products and sums wrap alike in both, so every draw is bit for bit the same on any device.

torch may also compute in ``float32`` (:func:`float_precision`): an option for speed on a device,
not the same numbers (docs/performance.md gives its measured error); numpy is always ``float64``.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import math
from collections.abc import Iterator
from typing import Any

import numpy as np

_MASK64 = (1 << 64) - 1


class NumpyNamespace:
    """numpy, with the few helpers the engine spells the same on every backend."""

    is_torch = False
    device = None
    precision = "float64"

    def __getattr__(self, name: str) -> Any:
        value = getattr(np, name)
        # found on the class from then on (a step asks for hundreds), never in an instance's
        # state (a namespace pickles and copies as before)
        setattr(NumpyNamespace, name, staticmethod(value))
        return value

    @staticmethod
    def copy(a: Any) -> Any:
        return np.array(a, copy=True)

    @staticmethod
    def astype(a: Any, dtype: Any) -> Any:
        return np.asarray(a).astype(dtype)

    @staticmethod
    def word(value: int) -> np.uint64:
        """A 64-bit word of the hash (``uint64``)."""
        return np.uint64(value & _MASK64)

    @staticmethod
    def words(a: Any) -> Any:
        """An array of 64-bit words (``uint64``) from numpy ``uint64`` or ``int64`` bits."""
        a = np.asarray(a)
        return a.view(np.uint64) if a.dtype == np.int64 else a.astype(np.uint64)

    @staticmethod
    def shift_right(a: Any, bits: int) -> Any:
        """The logical right shift of 64-bit words."""
        return a >> np.uint64(bits)

    @staticmethod
    def constant(values: tuple) -> Any:
        """Integers (a nested tuple, e.g. indices) as a read-only ``int64`` array, made once."""
        return _numpy_constant(values)

    @staticmethod
    def word_index(a: Any) -> Any:
        """Element indices as 64-bit words."""
        return np.asarray(a).astype(np.uint64)

    @staticmethod
    def to_numpy(a: Any) -> Any:
        return np.asarray(a)

    @staticmethod
    def dtype_kind(a: Any) -> str:
        """numpy's one-letter kind of the array's dtype (``"b"``, ``"i"``, ``"u"``, ``"f"``...)."""
        return np.asarray(a).dtype.kind


NUMPY = NumpyNamespace()


#: The device flags of the checks deferred in the current :func:`deferred_checks` block, or None.
_DEFERRED: list[Any] | None = None


@contextlib.contextmanager
def deferred_checks() -> Iterator[list[Any]]:
    """Run torch code with no question to the host: the checks that would read a device value
    (a Cholesky factorisation or inverse that failed, a covariance to repair, a batch with some
    update left out) take the path of a healthy batch, which gives the same numbers whenever every
    check passes, and append a device boolean to the yielded list instead. The caller reads
    :func:`all_passed` once, after the work, and redoes the step with the checks where it is False:
    what a step must do to run as a CUDA graph or under ``torch.compile``."""
    global _DEFERRED
    previous, _DEFERRED = _DEFERRED, []
    try:
        yield _DEFERRED
    finally:
        _DEFERRED = previous


def deferring() -> bool:
    """Whether the code runs inside :func:`deferred_checks`."""
    return _DEFERRED is not None


def defer(passed: Any) -> None:
    """Record a deferred check: ``passed`` is a device boolean tensor, True where it passed."""
    assert _DEFERRED is not None
    _DEFERRED.append(passed.all())


#: The float precisions of the torch engine; the first is the default and numpy's only one.
PRECISIONS = ("float64", "float32")

#: The precision of the torch floats made in the current :func:`float_precision` block (per
#: thread: two engines of different precisions may step in two threads).
_PRECISION: contextvars.ContextVar[str] = contextvars.ContextVar("precision", default="float64")


@contextlib.contextmanager
def float_precision(precision: str) -> Iterator[None]:
    """Inside the block, torch floats made by a :class:`TorchNamespace` without a dtype, or as
    ``np.float64``, or from numpy floats, are ``precision``'s (:data:`PRECISIONS`); the torch
    dtype itself (``xp.float64``) stays a double, as the random draws need. numpy is left as it
    is."""
    check_precision(precision, "cpu")
    token = _PRECISION.set(precision)
    try:
        yield
    finally:
        _PRECISION.reset(token)


_ELEMENTWISE: contextvars.ContextVar[bool | None] = contextvars.ContextVar("elementwise", default=None)


@contextlib.contextmanager
def elementwise_products(elementwise: bool) -> Iterator[None]:
    """Inside the block, a :class:`TorchNamespace` on any device computes einsums and batched
    matrix products as broadcast products summed (``True``) or with torch's library products
    (``False``). Outside, it does the first on CUDA only: on the CPU torch's library products
    make the eager step the faster (docs/performance.md, "Operations per step"); tests and the
    operation counts run the GPU's choice on the CPU through it."""
    if not isinstance(elementwise, bool):
        raise TypeError(f"elementwise_products takes True or False, got {elementwise!r}")
    token = _ELEMENTWISE.set(elementwise)
    try:
        yield
    finally:
        _ELEMENTWISE.reset(token)


def check_precision(precision: Any, device: Any) -> None:
    """Refuses, in one line, a precision not in :data:`PRECISIONS`, or ``float32`` on numpy
    (``device=None``)."""
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {', '.join(map(repr, PRECISIONS))}, got {precision!r}")
    if precision != "float64" and device is None:
        raise ValueError(
            f"precision={precision!r} runs on torch: give device='cpu' or 'cuda' (device=None, "
            "numpy, is float64 only)"
        )


def all_passed(flags: list[Any], xp: Any) -> Any:
    """The 0-d boolean, in namespace ``xp``, that every check of ``flags`` passed (True when
    there were none)."""
    return xp.all(xp.stack(flags)) if flags else xp.ones((), dtype=bool)


class _TorchLinalg:
    def __init__(self, torch: Any) -> None:
        self._torch = torch
        self.LinAlgError = torch.linalg.LinAlgError

    def cholesky(self, a: Any) -> Any:
        if deferring():
            factor, info = self._torch.linalg.cholesky_ex(a)
            defer(info == 0)
            return factor
        return self._torch.linalg.cholesky(a)

    def inv(self, a: Any) -> Any:
        if deferring():
            inverse, info = self._torch.linalg.inv_ex(a)
            defer(info == 0)
            return inverse
        return self._torch.linalg.inv(a)

    def eigh(self, a: Any) -> Any:
        return self._torch.linalg.eigh(a)

    def slogdet(self, a: Any) -> Any:
        return self._torch.linalg.slogdet(a)

    def norm(self, a: Any, axis: int | None = None, keepdims: bool = False) -> Any:
        return self._torch.linalg.vector_norm(a, dim=axis, keepdim=keepdims)


class TorchNamespace:
    """torch on one device, in the numpy spellings the engine uses.

    Arrays it creates are on its :attr:`device`, and floats unless told otherwise; its floats
    are ``float64``, or ``float32`` inside a :func:`float_precision` block.
    """

    is_torch = True

    def __init__(self, device: Any) -> None:
        import torch

        self.torch = torch
        self.device = torch.device(device)
        self.linalg = _TorchLinalg(torch)
        self._words: dict[int, Any] = {}
        self._constants: dict[tuple, Any] = {}
        self.pi, self.nan, self.inf = math.pi, math.nan, math.inf
        self.newaxis = None
        self.float64, self.int64, self.int8, self.bool_ = torch.float64, torch.int64, torch.int8, torch.bool
        for name in (
            "sqrt",
            "log",
            "log1p",
            "log10",
            "exp",
            "sin",
            "cos",
            "abs",
            "isfinite",
            "hypot",
            "swapaxes",
            "moveaxis",
            "broadcast_to",
            "zeros_like",
            "full_like",
            "tile",
        ):
            setattr(self, name, getattr(torch, name))
        self.arctan2 = torch.atan2
        self.mod = torch.remainder
        self.rint = torch.round

    def __repr__(self) -> str:
        return f"TorchNamespace({str(self.device)!r})"

    @property
    def precision(self) -> str:
        """The precision of the floats it makes now (:func:`float_precision`)."""
        return _PRECISION.get()

    # ------------------------------------------------------------ creation
    def _float(self) -> Any:
        return self.torch.float32 if _PRECISION.get() == "float32" else self.torch.float64

    def _dtype(self, dtype: Any) -> Any:
        if dtype is None:
            return self._float()
        if isinstance(dtype, self.torch.dtype):
            return dtype
        dtype = np.dtype(dtype)
        return self._float() if dtype == np.float64 else TORCH_DTYPES[dtype](self.torch)

    def asarray(self, a: Any, dtype: Any = None) -> Any:
        torch = self.torch
        if isinstance(a, np.ndarray) and a.dtype == np.uint64:
            a = a.view(np.int64)
        if isinstance(a, np.ndarray) and not a.flags.writeable:
            a = a.copy()
        tensor = torch.as_tensor(a, dtype=None if dtype is None else self._dtype(dtype), device=self.device)
        if dtype is None and tensor.dtype == torch.float64 and _PRECISION.get() == "float32":
            return tensor.to(torch.float32)
        return tensor

    def zeros(self, shape: Any, dtype: Any = None) -> Any:
        return self.torch.zeros(shape, dtype=self._dtype(dtype), device=self.device)

    def ones(self, shape: Any, dtype: Any = None) -> Any:
        return self.torch.ones(shape, dtype=self._dtype(dtype), device=self.device)

    def empty(self, shape: Any, dtype: Any = None) -> Any:
        return self.torch.empty(shape, dtype=self._dtype(dtype), device=self.device)

    def full(self, shape: Any, value: Any, dtype: Any = None) -> Any:
        if dtype is None and isinstance(value, bool | np.bool_):
            dtype = self.torch.bool
        return self.torch.full(
            shape if isinstance(shape, tuple) else (shape,),
            value,
            dtype=self._dtype(dtype),
            device=self.device,
        )

    def eye(self, n: int, dtype: Any = None) -> Any:
        return self.torch.eye(n, dtype=self._dtype(dtype), device=self.device)

    def arange(self, *args: int, dtype: Any = None) -> Any:
        return self.torch.arange(
            *args, dtype=self._dtype(dtype) if dtype is not None else self.torch.int64, device=self.device
        )

    @staticmethod
    def copy(a: Any) -> Any:
        return a.clone()

    @staticmethod
    def ascontiguousarray(a: Any) -> Any:
        return a.contiguous()

    def astype(self, a: Any, dtype: Any) -> Any:
        return a.to(self._dtype(dtype))

    # ------------------------------------------------------------ arithmetic
    def where(self, condition: Any, a: Any, b: Any) -> Any:
        torch = self.torch
        if isinstance(a, torch.Tensor) != isinstance(b, torch.Tensor) and isinstance(
            b if isinstance(a, torch.Tensor) else a, bool | int | float
        ):  # the scalar goes to the kernel as an argument: no tensor copied from the host (graphs)
            return torch.where(condition, a, b)
        if not isinstance(a, torch.Tensor):
            a = torch.as_tensor(a, dtype=b.dtype if isinstance(b, torch.Tensor) else None, device=self.device)
        if not isinstance(b, torch.Tensor):
            b = torch.as_tensor(b, dtype=a.dtype, device=self.device)
        return torch.where(condition, a, b)

    def maximum(self, a: Any, b: Any) -> Any:
        torch = self.torch
        if not isinstance(b, torch.Tensor):
            return torch.clamp(a, min=b)
        return torch.maximum(a, b)

    def minimum(self, a: Any, b: Any) -> Any:
        torch = self.torch
        if not isinstance(b, torch.Tensor):
            return torch.clamp(a, max=b)
        return torch.minimum(a, b)

    def clip(self, a: Any, low: Any, high: Any) -> Any:
        return self.torch.clamp(a, min=low, max=high)

    def stack(self, arrays: Any, axis: int = 0) -> Any:
        return self.torch.stack(list(arrays), dim=axis)

    def concatenate(self, arrays: Any, axis: int = 0) -> Any:
        return self.torch.cat(list(arrays), dim=axis)

    def broadcast_arrays(self, *arrays: Any) -> Any:
        return self.torch.broadcast_tensors(*arrays)

    def diagonal(self, a: Any, offset: int = 0, axis1: int = 0, axis2: int = 1) -> Any:
        return self.torch.diagonal(a, offset=offset, dim1=axis1, dim2=axis2)

    def trace(self, a: Any, axis1: int = 0, axis2: int = 1) -> Any:
        return self.torch.diagonal(a, dim1=axis1, dim2=axis2).sum(-1)

    # ------------------------------------------------------------ products
    @property
    def elementwise(self) -> bool:
        """Whether :meth:`einsum` and :meth:`matmul` compute elementwise: on CUDA, unless
        :func:`elementwise_products` says otherwise."""
        chosen = _ELEMENTWISE.get()
        return self.device.type == "cuda" if chosen is None else chosen

    def einsum(self, subscripts: str, *operands: Any) -> Any:
        """numpy's ``einsum``. Where :attr:`elementwise` and the operands broadcast over every
        index hold at most :data:`ELEMENTWISE_FACTOR` times the elements of the largest operand
        or of the result, their product summed over the indices left out: elementwise kernels,
        which ``torch.compile`` fuses with their neighbours (torch's own einsum calls a batched
        matrix product, whose library kernels are slow for millions of tiny matrices on a GPU).
        Else torch's ``einsum``."""
        # (the CPU's einsums go straight to torch's: no plan looked up on its hot path)
        plan = _einsum_plan(subscripts, tuple(o.ndim for o in operands)) if self.elementwise else None
        if plan is not None:
            letters, axes, summed = plan
            sizes: dict[str, int] = {}
            for operand, own in zip(operands, axes, strict=True):
                for letter, axis in own.items():
                    sizes[letter] = max(sizes.get(letter, 1), operand.shape[axis])
            result = math.prod(sizes[letter] for letter in letters[: len(letters) - len(summed)])
            largest = max(result, *(operand.numel() for operand in operands))
            if math.prod(sizes.values()) <= ELEMENTWISE_FACTOR * largest:
                product = None
                for operand, own in zip(operands, axes, strict=True):
                    view = operand.permute([own[letter] for letter in letters if letter in own])
                    view = view.reshape(
                        [operand.shape[own[letter]] if letter in own else 1 for letter in letters]
                    )
                    product = view if product is None else product * view
                return product.sum(dim=summed) if summed else product
        return self.torch.einsum(subscripts, *operands)

    def matmul(self, a: Any, b: Any) -> Any:
        """numpy's ``matmul`` (``a @ b``): where :attr:`elementwise`, for a batch of matrices or a
        vector, as :meth:`einsum` computes it (their broadcast product summed over the inner
        dimension, within its :data:`ELEMENTWISE_FACTOR`); else, and for two matrices alone, one
        library product (torch's)."""
        if (a.ndim == 2 and b.ndim == 2) or not self.elementwise:
            return self.torch.matmul(a, b)
        if b.ndim == 1:
            return self.einsum("...k,k->...", a, b)
        if a.ndim == 1:
            return self.einsum("k,...kn->...n", a, b)
        return self.einsum("...mk,...kn->...mn", a, b)

    # ------------------------------------------------------------ reductions
    def sum(self, a: Any, axis: Any = None, keepdims: bool = False) -> Any:
        return a.sum() if axis is None else a.sum(dim=axis, keepdim=keepdims)

    def max(self, a: Any, axis: Any = None, keepdims: bool = False) -> Any:
        return a.max() if axis is None else self.torch.amax(a, dim=axis, keepdim=keepdims)

    def min(self, a: Any, axis: Any = None, keepdims: bool = False) -> Any:
        return a.min() if axis is None else self.torch.amin(a, dim=axis, keepdim=keepdims)

    def any(self, a: Any, axis: Any = None) -> Any:
        return a.any() if axis is None else a.any(dim=axis)

    def all(self, a: Any, axis: Any = None) -> Any:
        return a.all() if axis is None else a.all(dim=axis)

    def argmax(self, a: Any, axis: int = -1) -> Any:
        return self.torch.argmax(a, dim=axis)

    def argmin(self, a: Any, axis: int = -1) -> Any:
        return self.torch.argmin(a, dim=axis)

    def argsort(self, a: Any, axis: int = -1, kind: str | None = None) -> Any:
        return self.torch.argsort(a, dim=axis, stable=True)

    def sort(self, a: Any, axis: int = -1) -> Any:
        return self.torch.sort(a, dim=axis).values

    def take_along_axis(self, a: Any, index: Any, axis: int) -> Any:
        """numpy's ``take_along_axis`` for indices in ``[0, size)``: one gather where ``index`` has
        ``a``'s shape off ``axis`` (torch's ``take_along_dim``, which broadcasts, first wraps every
        index, an operation more); there a negative index, which numpy wraps, is refused as out
        of range."""
        same = a.ndim == index.ndim and all(
            n == m for d, (n, m) in enumerate(zip(a.shape, index.shape, strict=True)) if d != axis % a.ndim
        )
        if same:
            return self.torch.gather(a, axis, index)
        return self.torch.take_along_dim(a, index, dim=axis)

    def put_along_axis(self, a: Any, index: Any, values: Any, axis: int) -> None:
        if isinstance(values, bool | int | float):  # an argument of the kernel: no tensor from the host
            a.scatter_(axis, index, values)
            return
        source = self.torch.as_tensor(values, dtype=a.dtype, device=self.device)
        a.scatter_(axis, index, source.expand_as(index))

    def repeat(self, a: Any, repeats: int, axis: int) -> Any:
        return self.torch.repeat_interleave(a, repeats, dim=axis)

    @staticmethod
    def reshape(a: Any, shape: Any) -> Any:
        return a.reshape(shape)

    def squeeze(self, a: Any, axis: int) -> Any:
        return a.squeeze(axis)

    def array_equal(self, a: Any, b: Any) -> bool:
        return bool(self.torch.equal(a, b))

    # ------------------------------------------------------------ the hash's words
    @staticmethod
    def word(value: int) -> int:
        """A 64-bit word of the hash: its bits as a signed ``int64`` Python integer."""
        value &= _MASK64
        return value - (1 << 64) if value >= 1 << 63 else value

    def constant(self, values: tuple) -> Any:
        """Integers (a nested tuple, e.g. indices) as an ``int64`` tensor on the device, made once:
        nothing is copied from the host when a step indexes with it (graphs)."""
        cached = self._constants.get(values)
        if cached is None:
            cached = self._constants[values] = self._made_once(values, self.torch.int64)
        return cached

    def word_array(self, value: int) -> Any:
        """A 64-bit word as a 0-d ``int64`` tensor on the device (made once per value)."""
        cached = self._words.get(value)
        if cached is None:
            cached = self._words[value] = self._made_once(self.word(value), self.torch.int64)
        return cached

    def _made_once(self, values: Any, dtype: Any) -> Any:
        """A real tensor of ``values`` to keep, whatever traces the code that first asks for it: made
        inside a step's trace (``make_fx``'s fake tensors), it would be a fake tensor, kept for the
        next env's steps in this process (the namespace is one per device)."""
        from torch.utils._python_dispatch import _disable_current_modes

        with _disable_current_modes():
            return self.torch.tensor(values, dtype=dtype, device=self.device)

    def words(self, a: Any) -> Any:
        """An ``int64`` tensor of 64-bit words from numpy ``uint64`` (or ``int64``) bits."""
        if isinstance(a, self.torch.Tensor):
            return a.to(self.device)
        a = np.asarray(a)
        return self.torch.as_tensor(
            a.view(np.int64) if a.dtype == np.uint64 else a.astype(np.int64), device=self.device
        )

    @staticmethod
    def shift_right(a: Any, bits: int) -> Any:
        """The logical right shift of 64-bit words held in ``int64``."""
        return (a >> bits) & ((1 << (64 - bits)) - 1)

    def word_index(self, a: Any) -> Any:
        return self.asarray(a, dtype=np.int64)

    @staticmethod
    def to_numpy(a: Any) -> Any:
        return a.detach().cpu().numpy()

    def dtype_kind(self, a: Any) -> str:
        torch = self.torch
        if a.dtype == torch.bool:
            return "b"
        if a.dtype.is_complex:
            return "c"
        if a.dtype.is_floating_point:
            return "f"
        return "u" if a.dtype == torch.uint8 else "i"

    @staticmethod
    def errstate(**_: Any) -> contextlib.nullcontext:
        return contextlib.nullcontext()


TORCH_DTYPES = {
    np.dtype(np.float64): lambda torch: torch.float64,
    np.dtype(np.float32): lambda torch: torch.float32,
    np.dtype(np.int64): lambda torch: torch.int64,
    np.dtype(np.int8): lambda torch: torch.int8,
    np.dtype(np.bool_): lambda torch: torch.bool,
}


#: How many times the elements of its largest operand (or result) the broadcast product of an
#: ``einsum`` or batched ``matmul`` may hold for :class:`TorchNamespace` to compute it
#: elementwise (the engine's are at most 9: a centralised update's innovation covariance over 9
#: sigma points); larger ones go to torch's matrix products.
ELEMENTWISE_FACTOR = 16


@functools.lru_cache(maxsize=256)
def _einsum_plan(
    subscripts: str, ndims: tuple[int, ...]
) -> tuple[str, tuple[dict[str, int], ...], tuple[int, ...]] | None:
    """How :meth:`TorchNamespace.einsum` broadcasts ``subscripts`` over operands of ``ndims``
    axes: every index in order (the output's, then those summed over; an ellipsis's axes named
    by characters no subscript uses), each operand's axis of each of its indices, and the
    positions summed over. None for what it leaves to torch: no ``->``, an index twice in one
    operand (a diagonal), or subscripts that do not fit the operands."""
    inputs, arrow, output = subscripts.replace(" ", "").partition("->")
    terms = inputs.split(",")
    if not arrow or len(terms) != len(ndims):
        return None
    named = [ndim - len(term.replace("...", "")) for term, ndim in zip(terms, ndims, strict=True)]
    ellipsis = "".join(chr(0x100 + d) for d in range(max(named, default=0)))
    terms = [
        term.replace("...", ellipsis[len(ellipsis) - count :] if count > 0 else "")
        for term, count in zip(terms, named, strict=True)
    ]
    output = output.replace("...", ellipsis)
    if any(len(set(term)) != len(term) or len(term) != ndim for term, ndim in zip(terms, ndims, strict=True)):
        return None
    if len(set(output)) != len(output) or not set(output) <= set("".join(terms)):
        return None
    summed = dict.fromkeys(letter for term in terms for letter in term if letter not in output)
    letters = output + "".join(summed)
    axes = tuple({letter: term.index(letter) for letter in term} for term in terms)
    return letters, axes, tuple(range(len(output), len(letters)))


@functools.lru_cache(maxsize=64)
def _numpy_constant(values: tuple) -> np.ndarray:
    array = np.array(values, dtype=np.int64)
    array.flags.writeable = False
    return array


@functools.lru_cache(maxsize=8)
def _torch_namespace(device: str) -> TorchNamespace:
    return TorchNamespace(device)


def device_namespace(device: Any) -> NumpyNamespace | TorchNamespace:
    """The namespace of ``device``: numpy for ``None``, else torch on that device (``"cpu"``,
    ``"cuda"``, ``"cuda:1"``, a ``torch.device``). Raises ``ValueError`` when torch is not
    installed or the device does not exist."""
    if device is None:
        return NUMPY
    try:
        import torch
    except ImportError:  # pragma: no cover - the test environments have torch
        raise ValueError(
            f"device={device!r} needs torch (pip install torch); device=None runs on numpy"
        ) from None
    try:
        resolved = torch.device(device)
    except (RuntimeError, TypeError):
        raise ValueError(f"device must be None, 'cpu', 'cuda' or 'cuda:N', got {device!r}") from None
    if resolved.type not in ("cpu", "cuda"):  # meta holds no values; mps and others lack float64 or tests
        raise ValueError(
            f"device must be None, 'cpu', 'cuda' or 'cuda:N', got {device!r} (torch's {resolved.type!r} "
            "devices are not supported)"
        )
    if resolved.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(f"device={device!r}: torch sees no CUDA device here; use 'cpu' or None")
        index = resolved.index or 0
        if index >= torch.cuda.device_count():
            raise ValueError(
                f"device={device!r}: torch sees {torch.cuda.device_count()} CUDA device(s) (0 .. "
                f"{torch.cuda.device_count() - 1})"
            )
        resolved = torch.device("cuda", index)
    return _torch_namespace(str(resolved))


def namespace(*arrays: Any) -> NumpyNamespace | TorchNamespace:
    """The namespace of the arrays: torch's (on the first tensor's device) if any is a torch
    tensor, numpy's otherwise."""
    for a in arrays:
        if type(a) is not np.ndarray and type(a).__module__.startswith("torch"):
            return _torch_namespace(str(a.device))
    return NUMPY
