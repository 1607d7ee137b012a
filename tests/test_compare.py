"""End-to-end comparisons with tiny budgets: the results.json contract, resume, failures."""

from __future__ import annotations

import json

import pytest

from scenarios.runs.results import summarise
from scenarios.runs.run import run_one
from scenarios.runs.spec import RecordOptions, RunSpec
from scenarios.sweep.backends import SweepError, run_local
from scenarios.sweep.run import PARTIAL, make_specs, run_sweep

RUN_KEYS = {"method", "seed", "world", "episodes_to_stable_optimal", "episodes_to_optimal",
            "optimal_test_fraction", "final_route_length", "epsilon_route_length",
            "success_rate", "reward_per_step", "reward_per_step_last_10pct", "wall_time_s",
            "env_steps", "steps_per_episode", "return_per_episode"}


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    out = tmp_path_factory.mktemp("cmp")
    specs = make_specs("paper-40", ["rnh-ql", "st-ql"], [0, 1], 40, ["grid"])
    results = run_sweep(specs, out, run_local, jobs=1)
    return out, specs, results


def test_results_json_contract(small):
    out, specs, _ = small
    data = json.loads((out / "results.json").read_text())
    assert {"version", "scenario", "world", "episodes", "optimal_route_length", "runs",
            "summary"} <= set(data)
    assert data["version"] == 2
    assert set(data["scenario"]["rewards"]) == {"scheme", "goal", "bump", "step"}
    assert data["episodes"] == 40 and data["world"] == "grid"
    assert data["optimal_route_length"] == 60
    assert len(data["runs"]) == len(specs) == 4
    for run in data["runs"]:
        assert RUN_KEYS <= set(run)
        assert len(run["steps_per_episode"]) == 40 == len(run["return_per_episode"])
        assert run["env_steps"] == sum(run["steps_per_episode"])
        # reward per step is total return / total steps, not a mean of per-episode ratios
        assert run["reward_per_step"] == pytest.approx(
            sum(run["return_per_episode"]) / sum(run["steps_per_episode"]), rel=1e-6)
    for method in ("rnh-ql", "st-ql"):
        entry = data["summary"][method]["grid"]
        assert entry["seeds"] == 2
        assert {"median", "q25", "q75", "ci95"} <= set(entry["wall_time_s"])
        lo, hi = entry["wall_time_s"]["ci95"]
        assert lo <= entry["wall_time_s"]["median"] <= hi
        assert 0.0 <= entry["optimal_route_fraction"] <= 1.0
    assert not (out / PARTIAL).exists()


def test_summary_and_figures_written(small):
    out, _, _ = small
    md = (out / "summary.md").read_text()
    assert "| rnh-ql | grid | 2 |" in md and "RNH-QL" in md
    for name in ("steps_per_episode", "reward_per_step", "time_per_episode", "routes",
                 "greedy_test"):
        assert (out / f"{name}.png").stat().st_size > 5000


def test_same_seed_same_record():
    spec = RunSpec("paper-40", "rnh-ql", 3, 30)
    a, b = run_one(spec), run_one(spec)
    for rec in (a, b):
        rec.pop("wall_time_s")
        rec.pop("wall_time_per_episode_s")
    assert a == b


def test_resume_skips_finished_runs(tmp_path):
    specs = make_specs("paper-40", ["st-ql"], [0, 1, 2], 20, ["grid"])
    first = run_one(specs[0])
    (tmp_path / PARTIAL).write_text(json.dumps(first) + "\n{torn line")
    seen = []

    def execute(todo, on_result=None):
        seen.extend(s.key for s in todo)
        return run_local(todo, jobs=1, on_result=on_result)

    results = run_sweep(specs, tmp_path, execute, resume=True, figures=False)
    assert seen == [specs[1].key, specs[2].key]
    assert [r["seed"] for r in results["runs"]] == [0, 1, 2]


def test_resume_after_a_finished_sweep_runs_only_what_is_new(tmp_path):
    specs = make_specs("paper-40", ["st-ql"], [0, 1], 10, ["grid"])
    run_sweep(specs, tmp_path, run_local, jobs=1, figures=False)
    more = make_specs("paper-40", ["st-ql"], [0, 1, 2], 10, ["grid"])
    seen = []

    def execute(todo, on_result=None):
        seen.extend(s.key for s in todo)
        return run_local(todo, jobs=1, on_result=on_result)

    results = run_sweep(more, tmp_path, execute, resume=True, figures=False)
    assert seen == [more[2].key]
    assert [r["seed"] for r in results["runs"]] == [0, 1, 2]


def test_a_failed_run_is_reported_and_the_others_kept(tmp_path):
    good = make_specs("paper-40", ["st-ql"], [0], 10, ["grid"])
    bad = RunSpec("paper-40", "st-ql", 1, 10, world="moon")
    with pytest.raises(SweepError) as info:
        run_sweep([*good, bad], tmp_path, run_local, jobs=1, figures=False)
    assert "world" in str(info.value) and bad.key in str(info.value)
    saved = [json.loads(line) for line in (tmp_path / PARTIAL).read_text().splitlines()]
    assert [r["key"] for r in saved] == [good[0].key]


def test_summary_counts_unreached_routes_as_never():
    runs = [{"method": "m", "world": "grid", "episodes_to_optimal": e, "final_route_length": n,
             "final_route_optimal": n == 10, "success_rate": 0.5, "wall_time_s": 1.0,
             "env_steps": 5, "optimal_action_fraction": 0.5}
            for e, n in ((None, -1), (100, 10), (300, 10))]
    e = summarise(runs)["m"]["grid"]
    assert e["episodes_to_optimal"]["median"] == 300
    assert e["optimal_route_fraction"] == pytest.approx(2 / 3)
    assert e["reached_goal_fraction"] == pytest.approx(2 / 3)


def test_atomic_writes_get_the_usual_file_mode(tmp_path):
    import os

    import numpy as np

    from learning.drivers.checkpoint import Checkpoint, save_checkpoint
    from learning.drivers.train import train_tabular
    from scenarios.runs.spec import load, make_config
    from sim.files import atomic_write_text

    umask = os.umask(0)
    os.umask(umask)
    atomic_write_text(tmp_path / "r.json", "{}")
    _, model = load("paper-40")
    rng = np.random.default_rng(0)
    result = train_tabular(make_config("st-ql"), model, 2, rng)
    save_checkpoint(tmp_path / "a.npz", Checkpoint.of_result(result, rng))
    for name in ("r.json", "a.npz"):  # mkstemp alone would leave 0o600
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o666 & ~umask


def test_run_key_covers_everything_that_changes_a_run(tmp_path):
    import dataclasses

    from tests.conftest import MAPS, REPO

    base = RunSpec(str(MAPS / "arena.map"), "rnh-ql", 0, 100, start=(3, 43), goal=(45, 5))
    variants = [dataclasses.replace(base, goal=(44, 5)), dataclasses.replace(base, start=(4, 43)),
                dataclasses.replace(base, test_every=5), dataclasses.replace(base, seed=1),
                dataclasses.replace(base, episodes=101), dataclasses.replace(base, world="physics"),
                dataclasses.replace(base, overrides=(("alpha", 0.2),))]
    keys = {base.key, *(v.key for v in variants)}
    assert len(keys) == 1 + len(variants)
    # recording options do not change the run, so they do not change the key
    assert dataclasses.replace(base, recording=RecordOptions("x.rrd", every=3)).key == base.key
    # the same name with other content (an edited TOML) is another run
    toml = (REPO / "sim" / "builtin" / "paper-40.toml").read_text()
    a, b = tmp_path / "a" / "s.toml", tmp_path / "b" / "s.toml"
    edited = toml.replace("steps_per_episode = 600", "steps_per_episode = 500")
    for path, text in ((a, toml), (b, edited)):
        path.parent.mkdir()
        path.write_text(text)
    ka, kb = RunSpec(str(a), "st-ql", 0, 10).key, RunSpec(str(b), "st-ql", 0, 10).key
    assert ka.split("#")[1] != kb.split("#")[1]


def test_one_quantile_definition_with_never_last():
    from scenarios.runs.statistics import quantile
    from scenarios.runs.statistics import seed_stats as _stats

    assert quantile([1, 2, 3, 4], 0.5) == 2.5  # type 7: interpolates
    assert quantile([4, 1, 3, 2], 0.25) == 1.75
    # never (None) sorts last; interpolating towards it is never, landing on a value is it
    assert quantile([1, 2, None, None], 0.5) == float("inf")
    assert quantile([1, 2, 3, None, None], 0.5) == 3.0
    stats = _stats([100, 200, None])
    assert {k: stats[k] for k in ("median", "q25", "q75")} == {"median": 200.0, "q25": 150.0,
                                                               "q75": None}
    # the median's bootstrap interval: a resample's median is 100 or never in 7/27 each
    assert stats["ci95"] == [100.0, None]
    # the same definition whether or not some seed never got there (positions 1.75 of 0..7)
    assert quantile([1, 2, 3, 4, None, None, None, None], 0.25) == 2.75


def test_resume_into_a_sweep_of_other_settings_is_refused(tmp_path, capsys):
    from scenarios.cli import main

    out = tmp_path / "o"
    base = ["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--out", str(out),
            "--jobs", "1"]
    assert main([*base, "--episodes", "4"]) == 0
    import json

    rec = json.loads((out / "results.json").read_text())["runs"][0]
    (out / "runs.partial.jsonl").write_text(json.dumps(rec) + "\n")  # a finished run of e4
    assert main([*base, "--episodes", "6", "--resume"]) == 2
    err = capsys.readouterr().err
    assert "another sweep" in err and "Traceback" not in err
    assert main([*base, "--episodes", "4", "--resume"]) == 0  # the same settings resume


def test_an_import_broken_by_ctrl_c_counts_as_ctrl_c():
    from scenarios.sweep.run import interrupted

    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as k:
            raise ImportError("initialization failed") from k
    except ImportError as err:
        assert interrupted(err)
    assert not interrupted(ImportError("no module named x"))


def test_a_maps_walls_are_drawn_as_one_image_not_a_patch_per_cell(tmp_path):
    """routes.png of a big map: its blocked cells are one image (ost003d has 24,422; a patch
    each took 11 s and grew with the map), drawn where the cells are."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from scenarios.figures.plots import draw_map
    from scenarios.runs.spec import load

    sc, model = load("maze-1")
    fig, ax = plt.subplots()
    draw_map(ax, sc, model)
    assert len(ax.patches) == len(sc.obstacles)  # circles only: no rectangle per cell
    walls = ax.images[-1].get_array()
    ix, iy = sc.blocked_cells[0]
    assert not walls.mask[iy, ix] and walls.mask.sum() == sc.nx * sc.ny - len(sc.blocked_cells)
    plt.close(fig)
