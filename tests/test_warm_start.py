"""Learn on the grid, finish on the robot: a physics run that starts from a learner trained in
the grid (api.train's init, compare's pretrain, the CLI's --init and --pretrain), for compiled
methods and plain-Python learners, counted phase by phase, resumable, refused with one line
when the learner cannot start this run."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rnhql
from scenarios import api
from scenarios.cli import main
from sim.errors import InputError

PORT = "tests.plain_learners.st_ql:STQLPort"
UNTIMED = ("wall_time_s", "wall_time_per_episode_s", "key")


def differing(a: dict, b: dict) -> list[str]:
    """Fields of two records that differ, wall-clock fields aside (the phase's own too)."""
    out = [k for k in a if k not in (*UNTIMED, "pretrain") and a[k] != b.get(k)]
    pa, pb = a.get("pretrain"), b.get("pretrain")
    if (pa is None) != (pb is None):
        return [*out, "pretrain"]
    if pa is not None:
        out += [f"pretrain.{k}" for k in pa if k != "wall_time_s" and pa[k] != pb.get(k)]
    return out


@pytest.mark.parametrize("method", ["haql", PORT])
def test_init_from_a_grid_run_is_the_sweeps_pretrained_run(method):
    """train(grid, seed) then train(physics, init=that run, seed) equals compare's
    pretrain=("grid", n) run of that seed: the learner and its streams continue."""
    grid = rnhql.train("paper-40", method, episodes=30, seed=3)
    warm = rnhql.train("paper-40", method, world="physics", fidelity="noisy", episodes=10,
                       seed=3, init=grid)
    swept = rnhql.compare("paper-40", [method], worlds="physics", fidelity="noisy", seeds=1,
                          seed_base=3, episodes=10, pretrain=("grid", 30), jobs=1)
    assert differing(dict(warm.record), dict(swept.runs[0].record)) == []
    pre = warm.pretrain
    assert pre["world"] == "grid" and pre["episodes"] == 30
    assert pre["env_steps"] == grid.record["env_steps"]  # the grid phase counted apart
    assert pre["final_route_length"] == grid.record["final_route_length"]
    assert 0.0 <= pre["policy"]["p_goal"] <= 1.0 and pre["policy"]["rollouts"] == 50
    assert warm.robot_primitives == sum(warm.record["steps_per_episode"])
    assert warm.robot_seconds == pytest.approx(sum(warm.record["sim_time_per_episode_s"]),
                                               abs=1e-3)
    assert warm.episodes == 10  # the rung's episodes, the grid's in pretrain


def test_a_warm_start_carries_the_learned_state():
    """The rung's phase starts where the grid left off: at exact (the grid's MDP) a learner
    that found the optimum in the grid keeps it from its first greedy test, while the
    same budget from scratch does not reach G; the Run that seeded it is unchanged."""
    grid = api.train("paper-40", "rnh-ql+", episodes=200, seed=0)
    assert grid.final_route_optimal
    q_before = grid.carried.state.q.copy()
    warm = api.train("paper-40", "rnh-ql+", world="physics", episodes=3, seed=0, init=grid)
    cold = api.train("paper-40", "rnh-ql+", world="physics", episodes=3, seed=0)
    assert warm.record["test_route_length"][0] == warm.optimal_route_length
    assert warm.final_route_optimal and not cold.final_route_optimal
    assert np.array_equal(grid.carried.state.q, q_before)


def test_cli_init_and_pretrain_give_the_apis_runs(tmp_path, capsys):
    """--save in the grid then --init in physics is api.train's init; --pretrain is compare's."""
    agent = tmp_path / "agent.npz"
    assert main(["train", "paper-40", "--method", "haql", "--episodes", "20", "--seed", "2",
                 "--save", str(agent)]) == 0
    assert main(["train", "paper-40", "--method", "haql", "--world", "physics", "--episodes",
                 "5", "--seed", "2", "--init", str(agent), "--json",
                 str(tmp_path / "run.json")]) == 0
    out = capsys.readouterr().out
    assert "first phase           20 grid episodes" in out and "robot time" in out
    cli = json.loads((tmp_path / "run.json").read_text())
    grid = api.train("paper-40", "haql", episodes=20, seed=2)
    lib = api.train("paper-40", "haql", world="physics", episodes=5, seed=2, init=grid)
    assert differing(cli, dict(lib.record)) == []
    lib_saved = api.train("paper-40", "haql", world="physics", episodes=5, seed=2, init=agent)
    assert differing(cli, dict(lib_saved.record)) == []

    assert main(["compare", "paper-40", "--methods", "haql", "--world", "physics", "--seeds",
                 "1", "--seed-base", "2", "--episodes", "5", "--pretrain", "grid:20",
                 "--jobs", "1", "--out", str(tmp_path / "cmp")]) == 0
    swept = json.loads((tmp_path / "cmp" / "results.json").read_text())["runs"][0]
    assert differing(cli, swept) == []
    assert "|pre-grid20" in swept["key"]
    summary = (tmp_path / "cmp" / "summary.md").read_text()
    assert "| haql | 20 [20, 20] episodes in grid, " in summary  # each phase, its currency
    assert "robot primitives | robot seconds |" in summary


def test_a_pretrained_sweep_resumes_after_an_interrupt(tmp_path, capsys):
    """A finished two-phase run is kept by --resume (its key names the grid phase), an
    unfinished one is run again from its seed: the same results as one uninterrupted run."""
    out = tmp_path / "cmp"
    argv = ["compare", "paper-40", "--methods", "haql,st-ql", "--world", "physics", "--seeds",
            "2", "--episodes", "4", "--pretrain", "grid:10", "--jobs", "1", "--out", str(out)]
    assert main(argv) == 0
    whole = json.loads((out / "results.json").read_text())["runs"]
    # as an interrupt leaves it: two runs finished, no results.json yet
    (out / "runs.partial.jsonl").write_text("".join(json.dumps(r) + "\n" for r in whole[:2]))
    (out / "results.json").unlink()
    assert main([*argv, "--resume"]) == 0
    again = json.loads((out / "results.json").read_text())["runs"]
    assert [differing(a, b) for a, b in zip(whole, again, strict=True)] == [[]] * 4
    # a sweep without the grid phase is another sweep: its --resume refuses these runs
    cold = [*argv[:argv.index("--pretrain")], *argv[argv.index("--pretrain") + 2:], "--resume"]
    assert main(cold) == 2
    assert "another sweep" in capsys.readouterr().err


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"world": "grid"}, "warm-starts a physics run"),
    ({"method": "st-ql"}, "is a haql learner"),
    ({"scenario": "paper-50"}, "1,600 cells"),
    ({"scenario": "rooms-1"}, "cells"),
])
def test_an_init_that_cannot_start_this_run_is_refused_before_any_work(kwargs, words):
    grid = api.train("paper-40", "haql", episodes=5, seed=0)
    call = {"scenario": "paper-40", "method": "haql", "world": "physics", **kwargs}
    with pytest.raises(InputError, match=words):
        api.train(call.pop("scenario"), call.pop("method"), episodes=1, init=grid, **call)


def test_an_init_from_another_layout_of_the_same_size_is_refused():
    """Same map size, another S: the layout digest tells them apart."""
    a = rnhql.Scenario(name="a", width_m=10.0, height_m=10.0, start=(1, 1), goal=(8, 8))
    b = rnhql.Scenario(name="b", width_m=10.0, height_m=10.0, start=(2, 1), goal=(8, 8))
    grid = api.train(a, "haql", episodes=5, seed=0)
    with pytest.raises(InputError, match="another scenario"):
        api.train(b, "haql", world="physics", episodes=1, init=grid)


def test_a_checkpoint_of_another_format_or_a_run_without_a_learner_is_refused(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_text("not an archive")
    with pytest.raises(ValueError, match="not an rnhql checkpoint"):
        api.train("paper-40", "haql", world="physics", episodes=1, init=bad)
    assert main(["train", "paper-40", "--method", "haql", "--world", "physics",
                 "--episodes", "1", "--init", str(bad)]) == 2
    read_back = api.Run.from_record(dict(api.train("paper-40", "haql", episodes=5).record))
    with pytest.raises(InputError, match="carries no learner"):
        api.train("paper-40", "haql", world="physics", episodes=1, init=read_back)
    with pytest.raises(InputError, match="pretrain"):
        api.compare("paper-40", ["haql"], pretrain=("grid", 5))  # grid-only sweep
    with pytest.raises(InputError, match="pretrain"):
        api.compare("paper-40", ["haql"], worlds="physics", pretrain=("physics", 5))


def test_a_pretrained_run_records_both_phases_in_one_recording(tmp_path):
    """The grid phase under grid_phase/ (its curves, routes and map), the rung's at the top."""
    pytest.importorskip("datafusion")
    import rerun as rr

    path = tmp_path / "two.rrd"
    run = api.train("paper-40", "haql", world="physics", fidelity="noisy", episodes=5,
                    pretrain=("grid", 20), record=path)
    assert run.recording == path and path.exists()
    with rr.server.Server(host="127.0.0.1", datasets={"d": [str(path)]}) as server:
        ds = server.client().get_dataset("d")
        cols = ds.filter_contents(["/**"]).reader(index="episode").to_arrow_table().column_names
    assert "/grid_phase/metrics/return:Scalars:scalars" in cols
    assert "/metrics/return:Scalars:scalars" in cols


def test_a_rung_run_saved_starts_the_next_rung(tmp_path):
    """Grid -> noisy (saved) -> slip from that file: a chain of levels, each a warm start; the
    saved physics agent loads (its state counts the grid's episodes too) and says its world."""
    grid = api.train("paper-40", "mf-r-max", episodes=20, seed=1)
    noisy = api.train("paper-40", "mf-r-max", world="physics", fidelity="noisy", episodes=3,
                      seed=1, init=grid, save=tmp_path / "noisy.npz")
    slip = api.train("paper-40", "mf-r-max", world="physics", fidelity="slip", episodes=2,
                     seed=1, init=tmp_path / "noisy.npz")
    assert slip.pretrain["world"] == "physics" and slip.pretrain["fidelity"] == "noisy"
    assert slip.pretrain["episodes"] == 23  # the learner's own count: grid and noisy
    same = api.train("paper-40", "mf-r-max", world="physics", fidelity="slip", episodes=2,
                     seed=1, init=noisy)  # the Run itself: the same learner, the same run
    a, b = dict(same.record), dict(slip.record)
    assert [k for k in a if k not in (*UNTIMED, "pretrain") and a[k] != b.get(k)] == []
    assert a["pretrain"]["policy"] == b["pretrain"]["policy"]


def test_an_init_under_other_rewards_is_refused():
    grid = api.train("paper-40", "haql", episodes=5, seed=0)  # goal-only
    with pytest.raises(InputError, match="learned under rewards"):
        api.train("paper-40", "haql", world="physics", episodes=1, init=grid, rewards="paper")


def test_mf_r_max_needs_m_rung_at_least_m():
    with pytest.raises(InputError, match="m_rung"):
        api.train("paper-40", "mf-r-max", episodes=1, settings={"m": 3, "m_rung": 2})
