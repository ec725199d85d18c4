"""The optional extras: the core imports and runs without them."""

import subprocess
import sys


def test_core_imports_and_runs_without_the_rl_extra():
    code = (
        "import sys; sys.modules['stable_baselines3'] = None; sys.modules['torch'] = None\n"
        "import gymnasium as gym, mimo_radar_env, agents, benchmarks.harness, mimo_radar_env.wrappers\n"
        "env = gym.make('MimoRadarSelect-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
        "from agents import PPOAgent\n"
        "from gymnasium.error import DependencyNotInstalled\n"
        "try:\n    PPOAgent('paper-1', 'x.zip')\nexcept DependencyNotInstalled as e:\n    print('ERR', e)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "ERR PPO needs stable_baselines3, in the rl extra" in result.stdout
