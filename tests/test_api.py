"""scenarios.api as a scenario script uses it: a Scenario built in Python, a plain-Python
learner beside the compiled methods, any policy graded, typed values back, and the same
records through the API as through the command."""

from __future__ import annotations

import itertools
import json
import os
from pathlib import Path

import numpy as np
import pytest

from scenarios import api
from sim.errors import InputError
from sim.scenario import Circle, Rewards, Scenario

PORT = "tests.plain_learners.st_ql:STQLPort"
UNTIMED = ("wall_time_s", "wall_time_per_episode_s")
NAMING = ("key", "method", "method_name", "config")


def small_world() -> Scenario:
    """A 12 x 12 arena with three circles, built in Python."""
    return Scenario(name="script-12", width_m=12.0, height_m=12.0, start=(1, 1), goal=(10, 10),
                    obstacles=(Circle(4.0, 4.0, 1.2), Circle(8.0, 7.0, 1.5),
                               Circle(3.0, 9.0, 1.0)),
                    steps_per_episode=200)


def same_runs(a: dict, b: dict, ignore: tuple[str, ...] = ()) -> list[str]:
    """The fields of two records that differ (wall-clock fields aside)."""
    return [k for k in a if k not in UNTIMED + ignore and a[k] != b.get(k)]


def test_a_python_port_of_st_ql_equals_compiled_st_ql_in_grid_and_physics():
    """The plain learner runs through the same machinery: equal draws, equal runs, figure for
    figure (grid, physics at exact, physics at noisy, in one sweep with the compiled
    method)."""
    cmp = api.compare("paper-40", ["st-ql", PORT], worlds=("grid", "physics"), seeds=2,
                      episodes=20, jobs=1)
    for world in ("grid", "physics"):
        for ours, theirs in zip(cmp.of("st-ql", world), cmp.of(PORT, world), strict=True):
            assert same_runs(dict(ours.record), dict(theirs.record), NAMING) == []
            assert np.array_equal(ours.policy, theirs.policy)
    noisy = api.compare("paper-40", ["st-ql", PORT], worlds="physics", fidelity="noisy",
                        seeds=1, episodes=10, jobs=1)
    a, b = noisy.runs
    assert same_runs(dict(a.record), dict(b.record), NAMING) == []
    assert a.p_goal is not None and a.p_goal == b.p_goal
    assert b.method_name == "ST-QL (Python)" and b.record["config"]["learner"] == PORT


def test_a_scenario_built_in_python_trains_compares_and_grades(tmp_path, monkeypatch):
    """The issue's scenario script: circles in Python, rnh-ql+ against a plain learner in
    grid and physics, a policy graded at noisy, typed values read back; nothing written."""
    from tests.plain_learners.st_ql import STQLPort

    monkeypatch.chdir(tmp_path)
    world = small_world()
    cmp = api.compare(world, ["rnh-ql+", STQLPort], worlds=["grid", "physics"], seeds=2,
                      episodes=30, jobs=1)
    assert list(tmp_path.iterdir()) == []  # out=None: no files
    assert isinstance(cmp, api.Comparison) and len(cmp.runs) == 8
    plus = cmp.of("rnh-ql+", "grid")
    assert [r.seed for r in plus] == [0, 1]
    mine = cmp.of(STQLPort, "physics")
    assert len(mine) == 2 and mine[0].method == "tests.plain_learners.st_ql:STQLPort"
    for r in cmp.runs:
        assert r.policy.shape == (144,) and r.policy.dtype == np.int64
        assert not r.policy.flags.writeable
        assert r.optimal_route_length > 0
        assert 0.0 <= r.success_rate <= 1.0
    assert "| rnh-ql+ | grid | 2 |" in cmp.summary()
    best = plus[0]
    assert best.final_route_length == best.optimal_route_length  # rnh-ql+ finds it here
    g = api.grade(best.policy, world, fidelity="noisy", drives=20, seed=0,
                  with_optimum=False)
    assert isinstance(g, api.Grade) and g.drives == 20 and 0.0 <= g.p_goal <= 1.0
    assert g.grid_route_length == best.final_route_length
    out = cmp.save(tmp_path / "saved")
    saved = json.loads((out / "results.json").read_text())
    assert [r["key"] for r in saved["runs"]] == [r.record["key"] for r in cmp.runs]
    assert (out / "summary.md").read_text() == cmp.summary()


def test_api_and_cli_write_the_same_results(tmp_path):
    """The command is a shell over the API: the same inputs give the same results.json."""
    from scenarios.cli import main

    argv = ["compare", "paper-40", "--methods", f"q-opt,{PORT}", "--seeds", "2",
            "--episodes", "20", "--jobs", "1", "--set", "eps=0.2"]
    assert main([*argv, "--out", str(tmp_path / "cli")]) == 0
    api.compare("paper-40", ["q-opt", PORT], seeds=2, episodes=20, jobs=1,
                settings={"eps": 0.2}, out=tmp_path / "api")
    cli = json.loads((tmp_path / "cli" / "results.json").read_text())
    lib = json.loads((tmp_path / "api" / "results.json").read_text())
    assert set(cli) == set(lib)
    assert [same_runs(a, b) for a, b in zip(cli["runs"], lib["runs"], strict=True)] == \
        [[], [], [], []]
    assert {k: v for k, v in cli.items() if k not in ("runs", "summary")} == \
        {k: v for k, v in lib.items() if k not in ("runs", "summary")}
    assert cli["runs"][0]["config"]["eps"] == 0.2  # q-opt took the setting
    assert cli["runs"][2]["config"] == {"learner": PORT, "eps": 0.1}  # the plain one has none


def test_train_returns_a_typed_run_equal_to_the_sweep_record(tmp_path):
    run = api.train("rooms-102", "q-opt", episodes=30, seed=1, save=tmp_path / "a.npz")
    assert isinstance(run, api.Run) and run.method == "q-opt" and run.episodes == 30
    assert run.optimal_route_length == 38 and run.world == "grid" and run.fidelity is None
    swept = api.compare("rooms-102", "q-opt", seeds=1, seed_base=1, episodes=30, jobs=1)
    assert same_runs(dict(run.record), dict(swept.runs[0].record)) == []
    graded = api.route(tmp_path / "a.npz", "rooms-102")
    assert graded.grid_route_length == run.final_route_length


def test_grade_is_the_tools_own_final_grade():
    """A physics run's final P(G) at noisy is grade(run.policy, seed=run.seed); a function of
    the cell grades as its table does."""
    world = small_world()
    run = api.train(world, "rnh-ql+", world="physics", fidelity="noisy", episodes=30, seed=3)
    assert run.p_goal is not None and run.p_goal > 0.5
    g = api.grade(run.policy, world, fidelity="noisy", seed=3, with_optimum=False)
    assert (g.p_goal, list(g.p_goal_ci95)) == (run.p_goal, list(run.p_goal_ci95))
    assert g.record["primitives_mean"] == run.record["final_policy"]["primitives_mean"]
    table = run.policy
    h = api.grade(lambda s: table[s], world, fidelity="noisy", seed=3, with_optimum=False)
    assert h == g


def test_optimum_and_grade_at_exact():
    from sim.grid import build_model
    from sim.grid.planning import bfs_route
    from sim.scenario_io import resolve_scenario

    opt = api.optimum("paper-40")
    assert opt.grid_route_length > 0 and opt.physics_route_length > 0
    assert opt.expected_primitives == opt.physics_route_length
    model = build_model(resolve_scenario("paper-40"))
    route = bfs_route(model.next_state, model.distance_to_goal, model.start)
    toward = np.zeros(model.n_states, np.int64)
    for s, s2 in itertools.pairwise(route):
        toward[s] = next(a for a in range(4) if model.next_state[s, a] == s2)
    g = api.grade(toward, "paper-40")
    assert g.drives == 1 and g.grid_route_length == opt.grid_route_length
    assert g.optimum == opt


@pytest.mark.parametrize("call, arg", [
    (lambda: api.compare("paper-40", seeds=0), "seeds"),
    (lambda: api.compare("paper-40", ["no-such"]), "method"),
    (lambda: api.compare("paper-40", ["st-ql", "st-ql"]), "methods"),
    (lambda: api.compare("paper-40", worlds=("grid", "moon")), "worlds"),
    (lambda: api.train("paper-40", "st-ql", episodes=0), "episodes"),
    (lambda: api.train("paper-40", "st-ql", seed="x"), "seed"),
    (lambda: api.train("paper-40", "st-ql", fidelity="noisy"), "fidelity"),
    (lambda: api.train("paper-40", "st-ql", rewards=5), "rewards"),
    (lambda: api.train("paper-40", "st-ql", settings={"eps": "high"}), "settings['eps']"),
    (lambda: api.train(42, "st-ql"), "scenario"),
    (lambda: api.train("paper-40", "st-ql", record="run.txt"), "record"),
    (lambda: api.grade(np.zeros(3, int), "paper-40"), "policy"),
    (lambda: api.grade(np.full(1600, 7), "paper-40"), "policy"),
    (lambda: api.grade(lambda s: "up", "paper-40"), "policy"),
    (lambda: api.compare("paper-40", resume=True), "resume"),
    (lambda: api.compare("paper-40", ["tests.plain_learners.st_ql:Nothing"]), "method"),
    (lambda: api.compare("paper-40", [dict]), "method"),
])
def test_bad_input_names_the_argument_and_the_fix(call, arg):
    with pytest.raises(InputError) as err:
        call()
    assert f": {arg}: " in str(err.value) and "Fix: " in str(err.value)


def test_objects_stand_for_their_text(tmp_path):
    """Path, Rewards and Fidelity objects work where their text does."""
    from sim.physics.fidelity import parse_fidelity
    from sim.scenario_io import builtin_dir

    path = Path(builtin_dir()) / "paper-40.toml"
    a = api.train(path, "st-ql", episodes=5, rewards=Rewards.preset("goal-only"))
    b = api.train("paper-40", "st-ql", episodes=5)
    assert same_runs(dict(a.record), dict(b.record), ("key",)) == []  # (named by its path)
    g = api.grade(a.policy, "paper-40", fidelity=parse_fidelity("noisy,wheel_noise=0.1"),
                  drives=2, with_optimum=False)
    text = api.grade(a.policy, "paper-40", fidelity="noisy,wheel_noise=0.1", drives=2,
                     with_optimum=False)
    assert g == text and g.fidelity.startswith("noisy+ (wheel_noise=0.1")


class _NoGreedy:
    """A plain learner with act and update only: what a first draft may look like."""

    def __init__(self, n_states, n_actions, rng):
        pass

    def act(self, s):
        return 0

    def update(self, s, a, r, s2, terminal):
        pass


def test_a_plain_learner_without_greedy_is_refused_with_what_to_add():
    with pytest.raises(InputError, match="has no greedy"):
        api.train("paper-40", _NoGreedy, episodes=5)


def test_a_learner_returning_a_bad_action_is_named():
    class Wild(_NoGreedy):
        def act(self, s):
            return 9

        def greedy(self, s):
            return 0

    with pytest.raises(ValueError, match=r"Wild.act\(\d+\) returned 9, not an action in 0..3"):
        api.train("paper-40", Wild, episodes=5)


def test_a_sweep_with_spawned_workers_runs_plain_and_external_methods():
    """Whatever the pool's start method: a spawned worker imports module:Class learners and
    registers the compiled methods this process registered from outside."""
    import sys

    from learning.methods.registry import register, unregister
    from tests import test_new_method as mod

    register(mod.Throwaway, sys.modules[mod.__name__], compared=False)
    try:
        cmp = api.compare("paper-40", [mod.Throwaway.cli, PORT, "st-ql"], seeds=1,
                          episodes=10, jobs=2, start_method="spawn")
    finally:
        unregister(mod.Throwaway.cli)
    port, compiled = cmp.of(PORT)[0], cmp.of("st-ql")[0]
    assert same_runs(dict(port.record), dict(compiled.record), NAMING) == []
    assert cmp.of(mod.Throwaway.cli)[0].method_name == "THROWAWAY-QL"


def test_a_plain_learners_run_records_and_shows_in_a_notebook(tmp_path, capsys, monkeypatch):
    """A plain learner's run is recorded like any (its q shown as the values); in Jupyter a
    Run shows its recording inline (Rerun's notebook viewer, the notebook extra)."""
    from tests.plain_learners.st_ql import STQLPort

    rrd = tmp_path / "port.rrd"
    run = api.train("paper-40", STQLPort, episodes=20, record=rrd)
    assert run.recording == rrd and rrd.stat().st_size > 10_000
    assert run.show() is None  # not a notebook: it says what to run instead
    assert f"rnhql view {rrd}" in capsys.readouterr().err
    pytest.importorskip("rerun_notebook")
    monkeypatch.setattr("scenarios.values._in_notebook", lambda: True)
    monkeypatch.delenv("RERUN_NOTEBOOK_ASSET", raising=False)
    viewer = run.show()
    assert type(viewer).__name__ == "Viewer"
    assert os.environ["RERUN_NOTEBOOK_ASSET"] == "serve-local"  # offline: served from here
    bare = api.train("paper-40", "st-ql", episodes=5)
    with pytest.raises(ValueError, match="no recording: pass record=True"):
        bare.show()


def test_a_sweep_with_a_plain_learner_resumes(tmp_path, capsys):
    """--resume keeps a plain learner's finished runs like any (its key names module:Class)."""
    out = tmp_path / "sweep"
    first = api.compare("paper-40", ["st-ql", PORT], seeds=2, episodes=10, jobs=1, out=out)
    again = api.compare("paper-40", ["st-ql", PORT], seeds=2, episodes=10, jobs=1, out=out,
                        resume=True)
    assert "4 of 4 runs already finished" in capsys.readouterr().err
    assert [dict(r.record) for r in again.runs] == [dict(r.record) for r in first.runs]


def test_compare_draws_the_greedy_test_the_ranking_reads(tmp_path):
    """greedy_test.png: per method the share of seeds whose greedy route from S is optimal at
    each test; the training curves say they count training episodes from random cells."""
    from scenarios.figures.plots import optimal_share, training_starts

    cmp = api.compare("paper-40", ["rnh-ql+", "st-ql"], seeds=2, episodes=40, jobs=1,
                      out=tmp_path / "c")
    assert (tmp_path / "c" / "greedy_test.png").stat().st_size > 5000
    runs = [dict(r.record) for r in cmp.of("rnh-ql+")]
    episodes, share = optimal_share(runs)
    assert list(episodes) == [10, 20, 30, 40]
    for k, e in enumerate(episodes):
        hits = [r["test_route_length"][k] == r["optimal_route_length"] for r in runs]
        assert share[k] == sum(hits) / len(runs) and runs[0]["test_episodes"][k] == e
    assert "random cells" in training_starts(dict(cmp.results))
