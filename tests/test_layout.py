"""Every module has a findable test: the test file that tests it, and a name from the module
that the test file uses (a witness that the mapping is not stale)."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: module -> (test file, a regular expression the test file must match)
# fmt: off
MODULE_TESTS = {
    "agents/base.py": ("tests/agents/test_base.py", r"make_agent"),
    "agents/costs.py": ("tests/benchmarks/test_resources.py", r"agents\.costs\."),
    "agents/fixed.py": ("tests/agents/test_oracle.py", r'"fix2"'),
    "agents/greedy.py": ("tests/agents/test_greedy.py", r"epsilon-greedy"),
    "agents/mg_crb_cl.py": ("tests/agents/test_mg_crb_cl.py", r"mg-crb-cl"),
    "agents/oracle.py": ("tests/agents/test_oracle.py", r'"best"'),
    "agents/parameters.py": ("tests/agents/solvers/test_bpso.py", r"must be an integer in"),
    "agents/networks.py": ("tests/agents/test_networks.py", r"RunningNormalization"),
    "agents/ppo.py": ("tests/agents/test_ppo.py", r"ppo:"),
    "agents/recency.py": ("tests/agents/test_recency.py", r'"rbe"'),
    "agents/rollout.py": ("tests/agents/test_rollout.py", r"Rollout"),
    "agents/registry.py": ("tests/agents/test_registry.py", r"available_agents|make_agent"),
    "agents/thompson.py": ("tests/agents/test_thompson.py", r'"cts"'),
    "agents/tracking.py": ("tests/agents/test_tracking.py", r"TrackingSelector"),
    "agents/ucb.py": ("tests/agents/test_ucb.py", r'"ucb1"'),
    "agents/uniform.py": ("tests/agents/test_base.py", r"available_agents"),
    "agents/solvers/alternating.py": ("tests/agents/solvers/test_alternating.py", r"AlternatingSolver"),
    "agents/solvers/base.py": ("tests/agents/solvers/test_base.py", r"make_solver"),
    "agents/solvers/bpso.py": ("tests/agents/solvers/test_bpso.py", r"BPSOSolver"),
    "agents/solvers/_bpso_kernels.py": ("tests/agents/solvers/test_bpso_kernels.py", r"_bpso_kernels"),
    "agents/solvers/exact.py": ("tests/agents/solvers/test_exact.py", r"ExactSolver"),
    "benchmarks/backends.py": ("tests/benchmarks/test_backends.py", r"workers=2"),
    "benchmarks/cli.py": ("tests/benchmarks/test_cli.py", r"main\("),
    "benchmarks/commands.py": ("tests/benchmarks/test_harness.py", r'"agents"'),
    "benchmarks/demo.py": ("tests/benchmarks/test_harness.py", r'"demo"'),
    "benchmarks/docs_tooling/pages.py": ("tests/clients/test_docs_tables.py", r"regenerate"),
    "benchmarks/docs_tooling/generators.py": ("tests/clients/test_docs_tables.py", r"calibration\.json"),
    "benchmarks/model_figures.py": ("tests/benchmarks/test_model_figures.py", r"brute"),
    "benchmarks/errors.py": ("tests/benchmarks/studies/test_settings.py", r"BenchError"),
    "benchmarks/harness.py": ("tests/benchmarks/test_harness.py", r"make_config"),
    "benchmarks/plots.py": ("tests/benchmarks/test_plots.py", r"plots\.palette"),
    "benchmarks/training.py": ("tests/agents/test_ppo.py", r"train_ppo"),
    "benchmarks/report.py": ("tests/benchmarks/test_report.py", r"format_estimate"),
    "benchmarks/shards.py": ("tests/benchmarks/test_shards.py", r"read_shard"),
    "benchmarks/uncertainty.py": ("tests/benchmarks/test_uncertainty.py", r"uncertainty\.estimate"),
    "benchmarks/verdicts.py": ("tests/benchmarks/test_verdicts.py", r"verdicts\.verdict"),
    "benchmarks/speed/policy_cost.py": ("tests/benchmarks/test_resources.py", r"measure_policy"),
    "benchmarks/speed/recipes.py": ("tests/clients/test_docs_recipes.py", r"run_recipe"),
    "benchmarks/studies/rl.py": ("tests/benchmarks/studies/test_rl.py", r"judge_learners"),
    "mimo_radar_env/tracking/planning.py": ("tests/mimo_radar_env/tracking/test_planning.py", r"Planner\("),
    "agents/planning.py": ("tests/mimo_radar_env/tracking/test_planning.py", r"plan-tracking"),
    "benchmarks/studies/planning.py": ("tests/benchmarks/studies/test_planning.py", r"planning"),
    "benchmarks/speed/planning_cost.py": ("tests/benchmarks/studies/test_planning.py", r"planning_cost"),
    "benchmarks/speed/device.py": ("tests/mimo_radar_env/test_device.py", r"episode_differences"),
    "benchmarks/speed/strong_scaling.py": ("tests/benchmarks/speed/test_strong_scaling.py", r"strong_scaling"),
    "benchmarks/speed/training_rate.py": ("tests/benchmarks/speed/test_training_rate.py", r"training_rate"),
    "benchmarks/training_log.py": ("tests/benchmarks/test_training_log.py", r"LearningCurve"),
    "benchmarks/torch_ppo.py": ("tests/benchmarks/test_torch_ppo.py", r"torch_ppo\.train|compute_gae"),
    "mimo_radar_env/core/arrays.py": ("tests/mimo_radar_env/test_device.py", r"device_namespace"),
    "benchmarks/speed/stages.py": ("tests/benchmarks/speed/test_stages.py", r"stages\.measure"),
    "benchmarks/speed/first_run.py": ("tests/benchmarks/speed/test_first_run.py", r"first_run"),
    "benchmarks/speed/env_throughput.py": ("tests/benchmarks/speed/test_perf.py", r"env_trial_steps_per_s"),
    "benchmarks/speed/perf.py": ("tests/benchmarks/speed/test_perf.py", r'"perf"'),
    "benchmarks/speed/scaling.py": ("tests/benchmarks/speed/test_scaling.py", r"scaling\.measure"),
    "benchmarks/studies/layout_search.py": ("tests/benchmarks/studies/test_layout_search.py", r"constraint_failure"),
    "benchmarks/studies/ablations.py": ("tests/benchmarks/studies/test_ablations.py", r"exploration_costs"),
    "benchmarks/studies/mechanisms.py": ("tests/benchmarks/studies/test_mechanisms.py", r"lead_and_sampling_oracles"),
    "benchmarks/precompile.py": ("tests/benchmarks/test_precompile.py", r"precompile\.all_kernels"),
    "benchmarks/speed/across_commits.py": ("tests/benchmarks/speed/test_across_commits.py", r"across_commits"),
    "benchmarks/speed/solver_speed.py": ("tests/benchmarks/speed/test_perf.py", r"bpso_optimality_rate"),
    "benchmarks/speed/tracker_speed.py": ("tests/benchmarks/speed/test_perf.py", r"tracker_speedup_vs_filterpy"),
    "benchmarks/studies/base.py": ("tests/benchmarks/studies/test_base.py", r"configure"),
    "benchmarks/studies/calibration.py": ("tests/benchmarks/studies/test_calibration.py", r"calibrate"),
    "benchmarks/studies/claims.py": ("tests/benchmarks/studies/test_claims.py", r"claims\.evaluate|claims\.judge"),
    "benchmarks/studies/paper.py": ("tests/benchmarks/test_harness.py", r'"paper"'),
    "benchmarks/studies/settings.py": ("tests/benchmarks/studies/test_settings.py", r"Settings\.from_args"),
    "benchmarks/studies/tracking.py": ("tests/benchmarks/studies/test_tracking.py", r"TRACKING_POLICIES"),
    "mimo_radar_env/core/compiled.py": ("tests/mimo_radar_env/tracking/fusion/test_average.py", r"HAVE_NUMBA"),
    "mimo_radar_env/core/_counter_hash_kernels.py": ("tests/mimo_radar_env/core/test_counter_hash.py", r"_nb\b|numba"),
    "mimo_radar_env/core/counter_hash.py": ("tests/mimo_radar_env/core/test_counter_hash.py", r"counter_hash"),
    "mimo_radar_env/core/geometry.py": ("tests/mimo_radar_env/core/test_geometry.py", r"measurement_jacobian"),
    "mimo_radar_env/core/model.py": ("tests/mimo_radar_env/core/test_model.py", r"RadarModel"),
    "mimo_radar_env/core/motion.py": ("tests/mimo_radar_env/core/test_motion.py", r"motion"),
    "mimo_radar_env/core/simulation.py": ("tests/mimo_radar_env/core/test_simulation.py", r"simulation"),
    "mimo_radar_env/core/streams.py": ("tests/mimo_radar_env/core/test_streams.py", r"TrialStreams"),
    "mimo_radar_env/core/superarm.py": ("tests/mimo_radar_env/core/test_superarm.py", r"exact_super_arm"),
    "mimo_radar_env/envs/cost.py": ("tests/benchmarks/test_resources.py", r"memory_parts"),
    "mimo_radar_env/envs/engine.py": ("tests/mimo_radar_env/envs/test_mimo_radar_select.py", r"vector_env"),
    "mimo_radar_env/envs/mimo_radar_select.py": ("tests/mimo_radar_env/envs/test_mimo_radar_select.py", r"MimoRadarSelect-v"),
    "mimo_radar_env/envs/options.py": ("tests/mimo_radar_env/envs/test_options.py", r"option_names"),
    "mimo_radar_env/envs/versions.py": ("tests/mimo_radar_env/envs/test_versions.py", r"VERSIONS"),
    "mimo_radar_env/extras.py": ("tests/agents/test_ppo.py", r"DependencyNotInstalled|extras"),
    "benchmarks/machine_rate.py": ("tests/benchmarks/test_machine_rate.py", r"machine_rate\.factor"),
    "benchmarks/metrics.py": ("tests/benchmarks/test_metrics.py", r"TrialMetrics"),
    "mimo_radar_env/rendering.py": ("tests/mimo_radar_env/envs/test_mimo_radar_select.py", r"rgb_array"),
    "mimo_radar_env/torchrl_env.py": ("tests/clients/test_packaging.py", r"MimoRadarSelectTorchRLEnv"),
    "mimo_radar_env/sb3.py": ("tests/agents/test_ppo.py", r"make_ppo_env"),
    "mimo_radar_env/scenarios/files.py": ("tests/mimo_radar_env/scenarios/test_files.py", r"yaml|toml"),
    "mimo_radar_env/scenarios/random_layouts.py": ("tests/mimo_radar_env/scenarios/test_random_layouts.py", r"random_scenario"),
    "mimo_radar_env/scenarios/scenario.py": ("tests/mimo_radar_env/scenarios/test_scenario.py", r"Scenario"),
    "mimo_radar_env/scenarios/validation.py": ("tests/mimo_radar_env/test_bad_input.py", r"ScenarioError"),
    "mimo_radar_env/tracking/bound.py": ("tests/mimo_radar_env/tracking/test_bound.py", r"bound_step"),
    "mimo_radar_env/tracking/_bound_kernels.py": ("tests/mimo_radar_env/tracking/test_bound.py", r"_compiled_step"),
    "mimo_radar_env/tracking/_selection_kernels.py": ("tests/mimo_radar_env/tracking/test_selection.py", r"super_arm_criterion\(\*args, use_numba=False\)"),
    "mimo_radar_env/tracking/fusion/_average_kernels.py": ("tests/mimo_radar_env/tracking/fusion/test_average.py", r"kernels\."),
    "mimo_radar_env/tracking/fusion/_centralized_kernels.py": ("tests/mimo_radar_env/tracking/fusion/test_centralized.py", r"kernels\."),
    "mimo_radar_env/tracking/fusion/average.py": ("tests/mimo_radar_env/tracking/fusion/test_average.py", r"average_channels"),
    "mimo_radar_env/tracking/fusion/base.py": ("tests/mimo_radar_env/tracking/test_imm_ukf.py", r"use_numba"),
    "mimo_radar_env/tracking/fusion/centralized.py": ("tests/mimo_radar_env/tracking/test_imm_ukf.py", r"centralized"),
    "mimo_radar_env/tracking/imm.py": ("tests/mimo_radar_env/tracking/test_imm_ukf.py", r"IMMUKFTracker"),
    "mimo_radar_env/tracking/imm_ukf.py": ("tests/mimo_radar_env/tracking/test_imm_ukf.py", r"filterpy"),
    "mimo_radar_env/tracking/information.py": ("tests/mimo_radar_env/tracking/test_selection.py", r"channel_information"),
    "mimo_radar_env/tracking/selection.py": ("tests/mimo_radar_env/tracking/test_selection.py", r"super_arm_criterion"),
    "mimo_radar_env/tracking/unscented.py": ("tests/mimo_radar_env/tracking/test_unscented.py", r"unscented_update"),
    "mimo_radar_env/wrappers/actions.py": ("tests/clients/test_clients.py", r"SuperArmDiscreteAction"),
    "mimo_radar_env/wrappers/features.py": ("tests/agents/test_ppo.py", r"features"),
    "mimo_radar_env/wrappers/flat.py": ("tests/mimo_radar_env/wrappers/test_flat.py", r"MimoRadarSelectFlatVectorEnv"),
}
# fmt: on


def _modules():
    for package in ("mimo_radar_env", "agents", "benchmarks"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path.name not in ("__init__.py", "__main__.py"):
                yield path.relative_to(ROOT).as_posix()


def test_every_module_is_mapped_to_its_tests():
    assert sorted(set(_modules()) - set(MODULE_TESTS)) == []
    assert sorted(set(MODULE_TESTS) - set(_modules())) == []


@pytest.mark.parametrize("module", sorted(MODULE_TESTS))
def test_each_mapped_test_file_exists_and_uses_the_module(module):
    test_file, witness = MODULE_TESTS[module]
    text = (ROOT / test_file).read_text()
    assert re.search(witness, text), f"{test_file} does not match {witness!r} for {module}"
