"""``examples/*.py`` run as pasted, at tiny budgets (``RNHQL_EXAMPLE_SCALE``), in a fresh
process from an empty folder. The Stable-Baselines3 ones need ``rnhql[sb3]`` (CI installs
it, with a CPU torch) and skip without it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
SB3_EXAMPLES = ["sb3_dqn_route.py", "sb3_ppo_diffdrive.py", "sb3_vec_env.py", "sb3_graded.py"]
SCRIPTS = ["script_circles.py", "script_own_learner.py", "script_grid_then_robot.py",
           "batched_dqn.py"]


def run_example(name: str, tmp_path: Path, scale: str = "0.01") -> str:
    env = {**os.environ, "RNHQL_EXAMPLE_SCALE": scale, "PYTHONPATH": str(REPO)}
    proc = subprocess.run([sys.executable, str(EXAMPLES / name)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_every_example_is_tested():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(["gym_loop.py",
                                                                     *SB3_EXAMPLES, *SCRIPTS])


def test_gym_loop(tmp_path):
    out = run_example("gym_loop.py", tmp_path)
    assert "PhysicsRoute: 20 primitives" in out
    assert "GridRoute: 484 states, optimal route 38 moves" in out
    assert "DiffDrive x8:" in out


@pytest.mark.parametrize("name", SB3_EXAMPLES)
def test_sb3_example(name, tmp_path):
    pytest.importorskip("stable_baselines3")
    out = run_example(name, tmp_path)
    expected = {"sb3_dqn_route.py": ["rnhql/GridRoute-v0: DQN", "rnhql/PhysicsRoute-v0: DQN"],
                "sb3_ppo_diffdrive.py": ["seed 0: ", " steps of PPO -> from S"],
                "sb3_vec_env.py": ["16 robots: SB3VecEnv", "DQN through SB3VecEnv"],
                "sb3_graded.py": ["DQN, 600 steps on the grid of three-pillars",
                                  "at exact, 1 drive(s): P(G)", "at noisy, 50 drive(s): P(G)",
                                  "at uncalibrated, 50 drive(s): P(G)", "V*(S) "]}[name]
    for line in expected:
        assert line in out, out


def test_script_circles(tmp_path):
    """A Scenario of circles built in Python, rnh-ql+ against haql in grid and physics at
    noisy, with a recording."""
    out = run_example("script_circles.py", tmp_path)
    for line in ("| rnh-ql+ | grid | 2 |", "| haql | physics | 2 |", "haql in physics: ",
                 "median P(G) ", "recording: recordings/pillars-20-compare.rrd"):
        assert line in out, out
    assert (tmp_path / "recordings" / "pillars-20-compare.rrd").stat().st_size > 10_000


def test_script_own_learner(tmp_path):
    """A plain-Python learner defined in the script, against rnh-ql+ and st-ql."""
    out = run_example("script_own_learner.py", tmp_path)
    for line in ("| COUNT-Q | grid | 2 |", "COUNT-Q: final route optimal in ",
                 "RNH-QL+: final route optimal in ", "ST-QL: final route optimal in "):
        assert line in out, out


def test_batched_dqn(tmp_path):
    """A DQN in torch written to the batched protocol, against rnh-ql+ in both worlds."""
    pytest.importorskip("torch")
    out = run_example("batched_dqn.py", tmp_path)
    for line in ("| rnh-ql+ | grid | 2 |", "| DQN (torch) | grid | 2 |",
                 "| DQN (torch) | physics | 2 |"):
        assert line in out, out


def test_python_api_train_and_route(tmp_path):
    """docs/python-api.md's scenarios.api calls, at a tiny budget: typed values back, bad
    input as an InputError naming the argument."""
    from scenarios import api
    from sim.errors import InputError

    agent = tmp_path / "agent.npz"
    run = api.train("rooms-102", "q-opt", episodes=30, seed=0, save=agent)
    assert run.method == "q-opt" and run.optimal_route_length == 38
    assert agent.exists()
    graded = api.route(agent, "rooms-102")
    assert graded.grid_route_length == run.final_route_length
    with pytest.raises(InputError, match="episodes"):
        api.train("rooms-102", episodes=0)
    with pytest.raises(InputError, match=": seed: is 'x', not a whole number"):
        api.train("rooms-102", seed="x")  # type: ignore[arg-type]


def test_python_api_compare(tmp_path):
    from scenarios import api

    cmp = api.compare("rooms-102", ["q-opt"], seeds=2, episodes=20, jobs=1,
                      out=tmp_path / "cmp")
    assert len(cmp.runs) == 2 and (tmp_path / "cmp" / "summary.md").exists()


def test_script_grid_then_robot(tmp_path):
    """A plain learner pretrained in the grid, finished at slip, against the rung alone."""
    out = run_example("script_grid_then_robot.py", tmp_path)
    for line in ("grid: COUNT-Q (grid, seed 0)", "the grid's policy at slip, before any robot "
                 "time: P(G) ", "grid, then robot: P(G) ", "robot only: P(G) ",
                 "robot time saved by the grid: "):
        assert line in out, out
