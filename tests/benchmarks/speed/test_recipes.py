"""The recipes of docs/clients.md and docs/ppo.md run as written, each alone in a fresh
interpreter with nothing imported beforehand (not under this suite's imports)."""

import pytest

from benchmarks.speed.recipes import OWN_ENVIRONMENT, recipes, run_recipe

RECIPES = recipes()
NEEDS = {
    "stable_baselines3": "rl extra",
    "sb3_contrib": "test extra",
    "SMPyBandits": "test extra",
    "stonesoup": "test extra",
}


def test_the_pages_have_recipes():
    assert {r.page for r in RECIPES} == {"clients.md", "ppo.md"} and len(RECIPES) >= 6


@pytest.mark.parametrize("recipe", RECIPES, ids=[r.key for r in RECIPES])
def test_recipe_runs_alone(recipe):
    for module, where in OWN_ENVIRONMENT.items():
        if recipe.imports(module):
            pytest.skip(f"the recipe needs {module}, which runs in {where}")
    for module, extra in NEEDS.items():
        if recipe.imports(module):
            pytest.importorskip(module, reason=f"the recipe needs {module} ({extra})")
    result, _ = run_recipe(recipe)
    assert result.returncode == 0, result.stderr[-3000:]


def test_a_recipe_changed_since_it_was_timed_fails_the_docs_check(tmp_path):
    import shutil

    from benchmarks.docs_tooling.generators import _recipe_costs
    from benchmarks.errors import BenchError
    from benchmarks.speed.recipes import DOCS

    docs = tmp_path / "docs"
    (docs / "results" / "perf").mkdir(parents=True)
    shutil.copy(DOCS / "results" / "perf" / "recipes.json", docs / "results" / "perf")
    for page in ("clients.md", "ppo.md"):
        shutil.copy(DOCS / page, docs / page)
    assert "| 1 |" in _recipe_costs(docs, "clients.md")  # as committed: timed as written
    text = (docs / "clients.md").read_text().replace("num_envs=64", "num_envs=65", 1)
    (docs / "clients.md").write_text(text)
    with pytest.raises(BenchError, match="the Python recipes of clients.md changed since"):
        _recipe_costs(docs, "clients.md")
