"""The array namespaces: numpy's, and torch's on a device, which gives numpy's numbers."""

import contextlib
import subprocess
import sys

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from mimo_radar_env.core.arrays import NUMPY, device_namespace, elementwise_products, namespace  # noqa: E402
from tests.helpers import vector_env  # noqa: E402

CPU = device_namespace("cpu")


def test_the_namespace_follows_the_arrays():
    assert namespace(np.zeros(2)) is NUMPY and device_namespace(None) is NUMPY
    assert namespace(np.zeros(2), torch.zeros(2)) is CPU


def test_the_numpy_namespace_hands_out_numpys_own_objects_and_pickles():
    """Its numpy names are numpy's objects (found on the class after the first lookup), and an
    instance holds none of them: it pickles and copies (a module would not)."""
    import copy
    import pickle

    for _ in range(2):  # looked up, then found on the class
        assert NUMPY.linalg is np.linalg and NUMPY.einsum is np.einsum
    assert NUMPY.sqrt is np.sqrt and NUMPY.pi == np.pi and vars(NUMPY) == {}
    assert pickle.loads(pickle.dumps(NUMPY)).linalg is np.linalg and copy.deepcopy(NUMPY).sqrt is np.sqrt
    with pytest.raises(AttributeError, match="no_such_function"):
        _ = NUMPY.no_such_function
    assert namespace(1.0, [2.0], np.float64(3.0)) is NUMPY


def test_the_torch_namespace_computes_what_numpy_does():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(3, 4, 5)), rng.normal(size=(3, 4, 5))
    index = np.argsort(a, axis=-1)[..., :2]
    by_rows = np.argsort(a, axis=1)[:, :2]
    cases = {
        "maximum": lambda xp, x, y: xp.maximum(x, y),
        "clip": lambda xp, x, y: xp.clip(x, -0.5, 0.5),
        "trace": lambda xp, x, y: xp.trace(x[..., :4], axis1=-2, axis2=-1),
        "sum": lambda xp, x, y: xp.sum(x, axis=(0, 2), keepdims=True),
        "argmin": lambda xp, x, y: xp.argmin(x, axis=1),
        "sort": lambda xp, x, y: xp.sort(x, axis=-1),
        "take": lambda xp, x, y: xp.take_along_axis(x, xp.asarray(index), axis=-1),
        "take, broadcast": lambda xp, x, y: xp.take_along_axis(x, xp.asarray(index[:1]), axis=-1),
        "take, axis 1": lambda xp, x, y: xp.take_along_axis(x, xp.asarray(by_rows), axis=1),
        "repeat": lambda xp, x, y: xp.repeat(x, 2, axis=1),
        "where": lambda xp, x, y: xp.where(x > y, x, y),
        "stack": lambda xp, x, y: xp.stack([x, y], axis=1),
    }
    for name, op in cases.items():
        expected = op(NUMPY, a, b)
        got = op(CPU, CPU.asarray(a), CPU.asarray(b))
        assert isinstance(got, torch.Tensor), name
        # a sum may add in another order: equal to rounding; every other op bit for bit
        rtol = 1e-15 if name in ("sum", "trace") else 0
        np.testing.assert_allclose(CPU.to_numpy(got), expected, rtol=rtol, atol=0, err_msg=name)


#: Every einsum the engine, the tracker and the agents write, with operands of their shapes.
EINSUMS = [
    ("k,bkc->b", [(3,), (5, 3, 6)]),
    ("bkij,bkid->bkjd", [(5, 2, 3, 3), (5, 2, 3, 4)]),
    ("bkij,bkjide->bkjde", [(5, 2, 3, 3), (5, 2, 3, 3, 4, 4)]),
    ("rij,bkrj->bkri", [(3, 4, 4), (5, 2, 3, 4)]),
    ("...r,...ri->...i", [(5, 2, 3), (5, 2, 3, 4)]),
    ("...r,...ri->...i", [(3,), (5, 2, 3, 4)]),  # an ellipsis that is empty in one operand
    ("...ij,...j,...kj->...ik", [(5, 2, 4, 4), (5, 2, 4), (5, 2, 4, 4)]),
    ("s,...sd->...d", [(9,), (5, 2, 3, 9, 6)]),
    ("...d,...d->...", [(5, 2, 3, 12), (5, 2, 3, 12)]),
    ("...s,...st,...t->...", [(5, 3, 9), (5, 3, 9, 9), (5, 3, 9)]),
    ("kij,bkj->bki", [(2, 4, 4), (5, 2, 4)]),
    ("...ji,...jk->...ik", [(5, 2, 6, 2, 2), (5, 2, 6, 2, 2)]),
    ("bamn,bkmnij->bkaij", [(5, 7, 4, 6), (5, 2, 4, 6, 2, 2)]),
    ("...m,...mn,...n->...", [(5, 8), (5, 8, 8), (5, 8)]),
]


def _library_products(function, *args, elementwise=True):
    """``function(*args)`` and how many matrix products of a library (bmm, mm) it called, with
    the products computed as on CUDA (``elementwise``; None: the device's own choice)."""
    from torch.utils._python_dispatch import TorchDispatchMode

    called = []

    class Products(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            if func.__name__.split(".")[0] in ("bmm", "mm", "addmm", "baddbmm", "matmul"):
                called.append(func.__name__)
            return func(*args, **(kwargs or {}))

    chosen = contextlib.nullcontext() if elementwise is None else elementwise_products(elementwise)
    with Products(), chosen:
        result = function(*args)
    return result, len(called)


def test_products_are_elementwise_on_cuda_and_torchs_on_the_cpu_unless_asked():
    from mimo_radar_env.core.arrays import TorchNamespace

    assert TorchNamespace("cuda").elementwise and not CPU.elementwise
    a = torch.ones(5, 3, 4, 4, dtype=torch.float64)
    with elementwise_products(True):
        assert CPU.elementwise
        with elementwise_products(False):
            assert not TorchNamespace("cuda").elementwise
    assert not CPU.elementwise
    for bad in ("yes", 1, None):
        with pytest.raises(TypeError, match="elementwise_products takes True or False, got"):
            with elementwise_products(bad):
                pass
    # torch's own on the CPU
    assert _library_products(CPU.matmul, a, a, elementwise=None)[1] == 1
    assert _library_products(CPU.einsum, "bkij,bkjl->bkil", a, a, elementwise=None)[1] == 1


@pytest.mark.parametrize(("subscripts", "shapes"), EINSUMS, ids=[s for s, _ in EINSUMS])
def test_the_torch_einsum_is_numpys_as_elementwise_products(subscripts, shapes):
    """numpy's einsum to round-off, computed as broadcast products summed (no library matrix
    product: torch's einsum calls a batched one for these)."""
    rng = np.random.default_rng(0)
    operands = [rng.normal(size=shape) for shape in shapes]
    ours, products = _library_products(CPU.einsum, subscripts, *map(torch.as_tensor, operands))
    np.testing.assert_allclose(ours.numpy(), np.einsum(subscripts, *operands), rtol=1e-13, atol=1e-13)
    assert products == 0
    _, theirs = _library_products(torch.einsum, subscripts, *map(torch.as_tensor, operands))
    assert theirs > 0  # what the elementwise form replaces


def test_a_large_contraction_or_a_diagonal_goes_to_torchs_einsum():
    """A product whose broadcast would hold more than ELEMENTWISE_FACTOR times its largest operand
    (a 64 x 64 matrix product: 64 times) calls torch's matrix product; a repeated index (a
    diagonal, which the broadcast cannot express) is torch's einsum too; both numpy's numbers."""
    from mimo_radar_env.core.arrays import ELEMENTWISE_FACTOR

    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(3, 64, 64)), rng.normal(size=(3, 64, 64))
    assert 64 > ELEMENTWISE_FACTOR
    ours, products = _library_products(CPU.einsum, "bij,bjk->bik", torch.as_tensor(a), torch.as_tensor(b))
    np.testing.assert_allclose(ours.numpy(), a @ b, rtol=1e-12)
    assert products == 1
    ours, products = _library_products(CPU.matmul, torch.as_tensor(a), torch.as_tensor(b))
    np.testing.assert_allclose(ours.numpy(), a @ b, rtol=1e-12)
    assert products == 1
    diagonal = CPU.einsum("bii->bi", torch.as_tensor(a))
    np.testing.assert_array_equal(diagonal.numpy(), np.einsum("bii->bi", a))


@pytest.mark.parametrize(
    ("a", "b", "products"),
    [((5, 3, 4, 9), (5, 3, 9, 2), 0), ((5, 3, 4), (4,), 0), ((4,), (5, 4, 2), 0), ((6, 4), (4, 600), 1)],
)
def test_the_torch_matmul_is_elementwise_for_batches_and_one_library_product_for_two_matrices(a, b, products):
    """numpy's ``a @ b``: a batch of small matrices (or a vector) as broadcast products summed;
    two matrices alone (the exact oracle's one product over every trial) torch's matmul."""
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=a), rng.normal(size=b)
    ours, called = _library_products(CPU.matmul, torch.as_tensor(a), torch.as_tensor(b))
    np.testing.assert_allclose(ours.numpy(), a @ b, rtol=1e-13, atol=1e-13)
    assert called == products


def test_the_torch_take_along_axis_is_one_gather_and_refuses_a_negative_index():
    """Where the index has the array's shape off the axis, one operation (torch's
    ``take_along_dim`` is two: it wraps every index first); a negative index, which numpy wraps,
    is refused there, not taken from the end."""
    from torch.utils._python_dispatch import TorchDispatchMode

    calls = []

    class Count(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            calls.append(str(func))
            return func(*args, **(kwargs or {}))

    table, index = CPU.asarray(np.arange(12.0).reshape(3, 4)), CPU.asarray(np.array([[3, 0]] * 3))
    with Count():
        taken = CPU.take_along_axis(table, index, axis=1)
    assert calls == ["aten.gather.default"]
    np.testing.assert_array_equal(CPU.to_numpy(taken), [[3.0, 0.0], [7.0, 4.0], [11.0, 8.0]])
    with pytest.raises(RuntimeError, match="out of bounds"):
        CPU.take_along_axis(table, CPU.asarray(np.array([[-1, 0]] * 3)), axis=1)


@pytest.mark.parametrize(
    ("device", "message"),
    [
        ("gpu", r"device must be None, 'cpu', 'cuda' or 'cuda:N', got 'gpu'"),
        ("cuda:7", "CUDA device"),
        # torch parses these, but meta tensors hold no values (the env stepped and returned them)
        ("meta", r"got 'meta' \(torch's 'meta' devices are not supported\)"),
        ("mps", r"got 'mps' \(torch's 'mps' devices are not supported\)"),
    ],
)
def test_a_device_that_is_not_there_is_refused_in_one_line(device, message):
    if device == "cuda:7" and torch.cuda.device_count() > 7:  # pragma: no cover
        pytest.skip("this machine has 8 GPUs")
    with pytest.raises(ValueError, match=message) as caught:
        vector_env("MimoRadarSelect-v1", 2, device=device)
    assert "\n" not in str(caught.value)


def test_device_none_needs_no_torch_and_a_device_without_torch_is_refused():
    script = (
        "import sys; sys.modules['torch'] = None\n"
        "import gymnasium as gym, numpy as np, mimo_radar_env\n"
        "env = gym.make_vec('MimoRadarSelect-v1', num_envs=2, vectorization_mode='vector_entry_point')\n"
        "env.reset(seed=0); env.step(env.oracle_action())\n"
        "try:\n"
        "    gym.make_vec('MimoRadarSelect-v1', num_envs=2, vectorization_mode='vector_entry_point',\n"
        "                 device='cpu')\n"
        "except ValueError as error:\n"
        "    print(error)\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True).stdout
    assert "device='cpu' needs torch" in out


def test_a_float_precision_block_holds_in_its_own_thread_only():
    """Two engines of different precisions may step in two threads: a float32 block in one leaves
    the other's floats float64."""
    import threading

    from mimo_radar_env.core.arrays import float_precision

    xp = CPU
    entered, looked = threading.Event(), threading.Event()
    seen = {}

    def other_thread():
        entered.wait(10)
        seen["other"] = xp.zeros(1).dtype
        looked.set()

    thread = threading.Thread(target=other_thread)
    thread.start()
    with float_precision("float32"):
        entered.set()
        assert looked.wait(10)
        seen["own"] = xp.zeros(1).dtype
    thread.join()
    assert seen == {"other": torch.float64, "own": torch.float32}
    assert xp.zeros(1).dtype == torch.float64  # the block's end restores it
