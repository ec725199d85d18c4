"""The tests mirror the packages: the tests of ``PACKAGE/PATH/NAME.py`` are in
``tests/PACKAGE/PATH/test_NAME.py``. A compiled twin ``_NAME_kernels.py`` is tested beside the
module it twins, in ``test_NAME.py`` (or a ``test_NAME_kernels.py`` of its own). Tests that cross
modules (golden numbers, clients, the docs site) sit where they fit, under names that say what
they check."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def expected_test_files(module: Path) -> list[Path]:
    """Where the tests of ``module`` (a path relative to the repository) may be."""
    folder = Path("tests") / module.parent
    name = module.stem
    if name.startswith("_") and name.endswith("_kernels"):
        return [folder / f"test_{name[1:]}.py", folder / f"test_{name[1 : -len('_kernels')]}.py"]
    return [folder / f"test_{name}.py"]


def _modules() -> list[Path]:
    return [
        path.relative_to(ROOT)
        for package in ("mimo_radar_env", "agents", "benchmarks")
        for path in sorted((ROOT / package).rglob("*.py"))
        if path.name not in ("__init__.py", "__main__.py")
    ]


def test_the_rule_maps_a_module_and_a_compiled_twin():
    assert expected_test_files(Path("agents/ucb.py")) == [Path("tests/agents/test_ucb.py")]
    assert expected_test_files(Path("mimo_radar_env/tracking/_bound_kernels.py")) == [
        Path("tests/mimo_radar_env/tracking/test_bound_kernels.py"),
        Path("tests/mimo_radar_env/tracking/test_bound.py"),
    ]


@pytest.mark.parametrize("module", _modules(), ids=str)
def test_every_module_has_its_test_file_in_the_mirror_folder(module):
    candidates = expected_test_files(module)
    assert any((ROOT / c).is_file() for c in candidates), f"{module}: none of {[str(c) for c in candidates]}"


#: The functions allowed over :data:`LONGEST_FUNCTION` lines, with why: compiled kernels (one loop
#: over trials that numba compiles whole) and data tables.
LONG_ON_PURPOSE = {
    ("agents/solvers/_bpso_kernels.py", "_run_numba"): "numba kernel",
    ("mimo_radar_env/tracking/fusion/_centralized_kernels.py", "_update"): "numba kernel",
    ("benchmarks/studies/claims.py", "paper_claims"): "the table of the paper's claims",
}
LONGEST_FUNCTION = 80


def test_no_function_runs_over_80_lines_but_kernels_and_tables():
    """A function of more than 80 lines does several jobs: split it (the compiled kernels and
    data tables of :data:`LONG_ON_PURPOSE` excepted, each of which is still that long)."""
    import ast

    long = {}
    for module in _modules():
        for node in ast.walk(ast.parse((ROOT / module).read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                if node.end_lineno - node.lineno + 1 > LONGEST_FUNCTION:
                    long[module.as_posix(), node.name] = node.end_lineno - node.lineno + 1
    assert sorted(set(long) - set(LONG_ON_PURPOSE)) == []
    assert sorted(set(LONG_ON_PURPOSE) - set(long)) == []  # an exception no longer needed goes
