"""The ablation script's judgement of issue 10's targets and the suite it runs on."""

from __future__ import annotations

import json
import math

from scenarios.experiments.ablation import compact_table, stable_optimal, verdict
from scenarios.experiments.suite import build_suite

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
    from scenarios.experiments.ablation import VARIANTS
    from scenarios.runs.spec import make_config

    plus = set(METHODS["rnh-ql+"]().fields())
    for label, method, overrides in VARIANTS:
        make_config(method, overrides)
        if method == "rnh-ql+ablation":
            assert {k for k, _ in overrides} - plus, label
