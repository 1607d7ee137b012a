"""``examples/*.py`` run as pasted, at tiny budgets (``RNHQL_EXAMPLE_SCALE``), in a fresh
process from an empty folder. The Stable-Baselines3 ones need ``rnhql[sb3]`` and are
``slow`` (``pytest -m slow tests/test_examples.py``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
SB3_EXAMPLES = ["sb3_dqn_route.py", "sb3_ppo_diffdrive.py", "sb3_vec_env.py"]


def run_example(name: str, tmp_path: Path, scale: str = "0.01") -> str:
    env = {**os.environ, "RNHQL_EXAMPLE_SCALE": scale, "PYTHONPATH": str(REPO)}
    proc = subprocess.run([sys.executable, str(EXAMPLES / name)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_every_example_is_tested():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(["gym_loop.py",
                                                                     *SB3_EXAMPLES])


def test_gym_loop(tmp_path):
    out = run_example("gym_loop.py", tmp_path)
    assert "PhysicsRoute: 20 primitives" in out
    assert "GridRoute: 484 states, optimal route 38 moves" in out
    assert "DiffDrive x8:" in out


@pytest.mark.slow
@pytest.mark.parametrize("name", SB3_EXAMPLES)
def test_sb3_example(name, tmp_path):
    pytest.importorskip("stable_baselines3")
    out = run_example(name, tmp_path)
    expected = {"sb3_dqn_route.py": ["rnhql/GridRoute-v0: DQN", "rnhql/PhysicsRoute-v0: DQN"],
                "sb3_ppo_diffdrive.py": ["seed 0: ", " steps of PPO -> from S"],
                "sb3_vec_env.py": ["16 robots: SB3VecEnv", "DQN through SB3VecEnv"]}[name]
    for line in expected:
        assert line in out, out


def test_python_api_train_and_route(tmp_path):
    """docs/python-api.md's scenarios.api calls, at a tiny budget: the CLI's work, values
    back, bad input as an InputError."""
    from scenarios import api
    from sim.errors import InputError

    agent = tmp_path / "agent.npz"
    run = api.train("rooms-102", "q-opt", episodes=30, seed=0, save=agent)
    assert run["method"] == "q-opt" and run["optimal_route_length"] == 38
    assert agent.exists()
    report = api.route(agent, "rooms-102")
    assert "BFS optimum: 38 moves" in report
    with pytest.raises(InputError, match="episodes"):
        api.train("rooms-102", episodes=0)
    with pytest.raises(InputError, match="invalid int"):
        api.train("rooms-102", seed="x")  # type: ignore[arg-type]


@pytest.mark.slow
def test_python_api_compare(tmp_path):
    from scenarios import api

    res = api.compare("rooms-102", tmp_path / "cmp", ["q-opt"], seeds=2, episodes=20, jobs=1)
    assert len(res["runs"]) == 2 and (tmp_path / "cmp" / "summary.md").exists()
