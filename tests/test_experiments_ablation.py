"""The ablation script's judgement of its targets and the suite it runs on."""

from __future__ import annotations

import json
import math

import pytest

from scenarios.studies.maps.ablation import compact_table, stable_optimal, verdict
from scenarios.studies.maps.suite import build_suite

MAPS = [dict(name="paper-40", held_out=False), dict(name="paper-50", held_out=False),
        dict(name="maze-101", held_out=True)]


def _cell(opt: int, med: float) -> dict:
    return dict(optimal_seeds=opt, seeds=10, median=med, q25=med, q75=med)


def test_verdict_names_every_missed_target():
    summary = {
        "x (= rnh-ql+)": {"paper-40": _cell(10, 40), "paper-50": _cell(10, 700),
                          "maze-101": _cell(8, 300)},
        "dyna-q": {"paper-40": _cell(9, 900), "paper-50": _cell(10, 600),
                   "maze-101": _cell(10, 200)},
    }
    ours, ref = verdict(summary, MAPS, "x (= rnh-ql+)", "dyna-q", 9)
    assert "on 2/3 maps (short on maze-101)" in ours
    assert "above 650 on paper-50" in ours
    assert "at least as many optimal seeds on 2/3 maps (fewer on maze-101)" in ref
    assert "fewer median episodes on 1/3, more on paper-50, maze-101" in ref


def test_verdict_when_every_target_is_met():
    summary = {"x": {n["name"]: _cell(10, 50) for n in MAPS},
               "dyna-q": {n["name"]: _cell(9, 500) for n in MAPS}}
    ours, ref = verdict(summary, MAPS, "x", "dyna-q", 9)
    assert "on 3/3 maps;" in ours and "(all ≤ 650)" in ours
    assert "on 3/3 maps; fewer median episodes on 3/3" in ref and "more on" not in ref


def test_compact_table_counts_maps_and_marks_never():
    summary = {"v": {"paper-40": _cell(10, 40), "paper-50": _cell(3, math.inf)}}
    tab = compact_table(summary, MAPS, ["v"], 9).splitlines()
    assert tab[0].endswith("| maze-101* | maps ≥ 9 |")
    assert tab[2] == "| v | 10 · 40 | 3 · — |  | 1/2 |"


def test_stable_optimal_is_the_first_test_after_which_every_test_is_optimal():
    assert stable_optimal([10, 20, 30, 40], [80, 80, 90, 80], 80) == 40
    assert stable_optimal([10, 20, 30], [80, 80, 80], 80) == 10
    assert stable_optimal([10, 20], [80, 90], 80) is None


def test_suite_held_out_maps_are_generated_from_the_seeds_asked_for(tmp_path):
    entries = build_suite(tmp_path, "goal-only", moving_ai=False, held_out_seeds=(103,))
    names = {e["name"]: e for e in entries}
    assert {"maze-1", "rooms-2", "maze-103", "rooms-103"} <= set(names)
    assert "maze-101" not in names
    assert names["maze-103"]["held_out"] and not names["maze-1"]["held_out"]
    for e in entries:  # start and goal far apart, room to explore in an episode
        assert e["optimal"] > 0 and e["steps_per_episode"] >= max(600, 4 * e["optimal"])
    assert json.loads((tmp_path / "suite.json").read_text()) == entries


def test_verdict_without_the_open_maps_says_nothing_about_them():
    maps = [dict(name="maze-103", held_out=True)]
    summary = {"x": {"maze-103": _cell(10, 50)}}
    (ours,) = verdict(summary, maps, "x", "dyna-q", 9)
    assert ours == "- `x`: ≥ 9 optimal seeds on 1/1 maps"


def test_every_variant_is_a_config_of_its_method_and_the_ablations_rows_need_it():
    """A row runs on rnh-ql+ablation only where it turns a switch rnh-ql+ has not."""
    from learning import METHODS
    from scenarios.runs.spec import make_config
    from scenarios.studies.maps.ablation import VARIANTS

    plus = set(METHODS["rnh-ql+"]().fields())
    for label, method, overrides in VARIANTS:
        make_config(method, overrides)
        if method == "rnh-ql+ablation":
            assert {k for k, _ in overrides} - plus, label


RUN_FIELDS = ["map", "label", "seed", "optimal", "final_route_optimal", "final_route_length",
              "first_optimal", "stable_optimal", "env_steps", "wall_time_s", "episodes"]
TINY = ["--seeds", "2", "--episodes", "20", "--jobs", "1", "--maps", "paper-40,maze-1",
        "--variants", "0,11"]


def _without_wall(data):
    """An ablation.json without its timings and map paths (another --out)."""
    return {**data, "runs": [{k: v for k, v in r.items() if k != "wall_time_s"}
                             for r in data["runs"]],
            "maps": [{k: v for k, v in m.items() if k != "file"} for m in data["maps"]]}


def test_ablation_runs_as_a_sweep_and_writes_its_files(tmp_path, capsys):
    """The ablation's files and their shape; each run's figures are its record's."""
    from scenarios.runs.run import run_one
    from scenarios.runs.spec import RunSpec, load
    from scenarios.studies.maps.ablation import VARIANTS, main
    from scenarios.sweep.run import PARTIAL

    out = tmp_path / "abl"
    assert main(["--out", str(out), *TINY]) == 0
    data = json.loads((out / "ablation.json").read_text())
    assert list(data) == ["maps", "variants", "summary", "runs"]
    assert [m["name"] for m in data["maps"]] == ["paper-40", "maze-1"]
    labels = [VARIANTS[0][0], VARIANTS[11][0]]
    assert [v["label"] for v in data["variants"]] == labels
    assert list(data["summary"]) == labels
    assert data["summary"][labels[1]]["maze-1"]["seeds"] == 2
    assert len(data["runs"]) == 2 * 2 * 2
    for r in data["runs"]:
        assert list(r) == RUN_FIELDS and r["episodes"] == 20
    # the first run, as the ablation computed it before it ran on run_sweep
    first = data["runs"][0]
    path = data["maps"][0]["file"]
    rec = run_one(RunSpec(path, "rnh-ql", 0, 20))
    opt = int(load(path)[1].optimal_route_length)
    assert {k: v for k, v in first.items() if k != "wall_time_s"} == dict(
        map="paper-40", label=labels[0], seed=0, optimal=opt,
        final_route_optimal=bool(rec["final_route_optimal"]),
        final_route_length=rec["final_route_length"], first_optimal=rec["episodes_to_optimal"],
        stable_optimal=stable_optimal(rec["test_episodes"], rec["test_route_length"], opt),
        env_steps=rec["env_steps"], episodes=20)
    md = (out / "ablation.md").read_text()
    assert md.startswith("Rewards `goal-only`, 2 seeds x 20 episodes.") and "Compact" in md
    assert (out / "ablation.png").stat().st_size > 5000
    assert not (out / PARTIAL).exists()
    assert md in capsys.readouterr().out


def test_ablation_interrupted_then_resumed_writes_what_one_pass_writes(tmp_path, monkeypatch):
    from scenarios.studies.maps.ablation import main
    from scenarios.sweep import backends
    from scenarios.sweep.run import PARTIAL

    whole = tmp_path / "whole"
    assert main(["--out", str(whole), *TINY]) == 0
    real = backends.run_local
    seen = []

    def stop_after_two(todo, on_result=None, **kw):
        seen.append(len(todo))
        done: list = []

        def save(rec):  # Ctrl-C as the second run is saved
            on_result(rec)
            done.append(rec)
            if len(done) == 2:
                raise KeyboardInterrupt
        return real(todo, on_result=save, **kw)

    monkeypatch.setattr(backends, "run_local", stop_after_two)
    out = tmp_path / "cut"
    with pytest.raises(KeyboardInterrupt):
        main(["--out", str(out), *TINY])
    kept = [json.loads(line) for line in (out / PARTIAL).read_text().splitlines()]
    assert len(kept) == 2 and "steps_per_episode" not in kept[0]  # the kept figures only
    assert not (out / "ablation.json").exists()
    monkeypatch.setattr(backends, "run_local", lambda todo, **kw: seen.append(len(todo))
                        or real(todo, **kw))
    assert main(["--out", str(out), *TINY, "--resume"]) == 0
    assert seen == [8, 6]
    assert _without_wall(json.loads((out / "ablation.json").read_text())) == _without_wall(
        json.loads((whole / "ablation.json").read_text()))
    assert (out / "ablation.md").read_text() == (whole / "ablation.md").read_text()
