"""The held-out study: its problems, methods and table."""

from __future__ import annotations

import json
import re

import pytest

from scenarios.studies.maps import heldout
from scenarios.sweep.backends import run_local
from scenarios.sweep.kept import KEPT_FIELDS
from scenarios.sweep.resume_state import ResumeStateError
from scenarios.sweep.run import make_specs, run_sweep


def test_problems_and_methods_parse():
    assert heldout.share_of("uniform") == 0.0 and heldout.share_of("s10") == 0.1
    assert heldout.method_of("rnh-ql+:model_acting=1;sweeping=1") == (
        "rnh-ql+", (("model_acting", 1.0), ("sweeping", 1.0)))
    assert heldout.method_of("haql") == ("haql", ())
    free, stem = heldout.problem_map("maze-w4-64", 37, 0.02)
    assert free.shape == (64, 64) and stem == "maze-w4-64-s37-b0.02"
    with pytest.raises(ValueError, match="maze-wW-N"):
        heldout.problem_map("forest-64", 0, 0.0)
    with pytest.raises(ValueError, match="uniform"):
        heldout.share_of("half")


def test_the_study_runs_and_prints_its_table(tmp_path, capsys):
    out = tmp_path / "h"
    toml, _, _ = heldout.write_problem("maze-w2-24", 0.0, 5, 0.0, tmp_path / "own")
    problems = f"maze-w2-24@s20,maze-w2-24@uniform,rooms-102@uniform,{toml}@uniform"
    assert heldout.main(["--out", str(out), "--problems", problems, "--suite-episodes", "30",
                         "--methods", "rnh-ql+,rnh-ql+:model_acting=1", "--seeds", "1"]) == 0
    text = (out / "heldout.md").read_text()
    assert text in capsys.readouterr().out
    assert "| rnh-ql+:model_acting=1 |" in text and "maze-w2-24 uniform" in text
    assert text.count(" s |") == 2 * 4  # 2 methods x 4 problems
    assert "rooms-102 uniform (route 38)" in text
    assert "**Uniform starts**, 3 maps" in text and "**20 % of starts from S**, 1 map:" in text
    assert "| rnh-ql+ | " in text.split("**Uniform starts**")[1]  # a ranking row
    assert "Per map, the method with the lowest median" in text


def test_the_study_keeps_only_what_it_reads_and_resumes_from_it(tmp_path, capsys):
    """A run's record drops its greedy policy and per-episode series (what makes a 512²
    folder 500 MB); --resume reads the kept records back, and whole records written by a
    comparison, and runs nothing again."""
    out = tmp_path / "h"
    argv = ["--out", str(out), "--problems", "maze-w2-24@uniform", "--suite-episodes", "30",
            "--methods", "st-ql", "--seeds", "2"]
    assert heldout.main(argv) == 0
    table = (out / "heldout.md").read_text()
    [results] = out.glob("*/st-ql/results.json")
    runs = json.loads(results.read_text())["runs"]
    grid_only = set(KEPT_FIELDS) - {"final_policy", "robot_seconds", "pretrain"}
    assert len(runs) == 2 and all(set(r) == grid_only for r in runs)
    capsys.readouterr()
    assert heldout.main([*argv, "--resume"]) == 0
    assert "resuming: 2 of 2 runs already finished" in capsys.readouterr().err
    assert (out / "heldout.md").read_text() == table
    # a folder a comparison wrote (whole records) is resumed the same way
    whole = tmp_path / "whole"
    spec_dir = results.parent.parent.name
    toml, _, episodes = heldout.write_problem("maze-w2-24", 0.0, 37, 0.02, whole / "maps")
    run_sweep(make_specs(str(toml), ["st-ql"], [0, 1], episodes, ["grid"],
                         rewards="goal-only", s_starts=0.0),
              whole / spec_dir / "st-ql", run_local, figures=False, progress=None)
    assert "greedy_policy" in json.loads((whole / spec_dir / "st-ql" / "results.json"
                                          ).read_text())["runs"][0]
    assert heldout.main([*argv[:1], str(whole), *argv[2:], "--resume"]) == 0
    assert "resuming: 2 of 2 runs already finished" in capsys.readouterr().err
    assert all(set(r) == grid_only for r in json.loads(
        (whole / spec_dir / "st-ql" / "results.json").read_text())["runs"])
    # the same table but for the wall times (those runs ran again, on their own)
    wall = re.compile(r" · [0-9.]+ s \|")
    assert wall.sub(" |", (whole / "heldout.md").read_text()) == wall.sub(" |", table)


def test_a_kept_run_read_back_from_the_partial_file_is_checked(tmp_path, capsys):
    """After Ctrl-C the kept runs wait in runs.partial.jsonl: --resume runs only the rest,
    and a line that lacks a field the summary reads is refused, naming the line."""
    out = tmp_path / "h"
    argv = ["--out", str(out), "--problems", "maze-w2-24@uniform", "--methods", "st-ql",
            "--seeds", "2"]
    assert heldout.main(argv) == 0
    [folder] = out.glob("*/st-ql")
    runs = json.loads((folder / "results.json").read_text())["runs"]
    (folder / "results.json").unlink()
    (folder / "runs.partial.jsonl").write_text(json.dumps(runs[0]) + "\n")
    capsys.readouterr()
    assert heldout.main([*argv, "--resume"]) == 0
    assert "resuming: 1 of 2 runs already finished" in capsys.readouterr().err
    (folder / "results.json").unlink()
    lacking = {k: v for k, v in runs[0].items() if k != "episodes_to_stable_optimal"}
    (folder / "runs.partial.jsonl").write_text(json.dumps(lacking) + "\n\n")
    with pytest.raises(ResumeStateError, match=r"line 1.*episodes_to_stable_optimal"):
        heldout.main([*argv, "--resume"])


def test_the_ranking_orders_by_iqm_and_names_each_maps_winner():
    """Shares of the budget (never: all of it); the IQM orders the methods, the
    probability of improvement is complementary, a map's winner has the lowest median."""
    from scenarios.studies.maps.ranking import profile, ranking, shares

    assert shares([10, None, 200], 100) == [0.1, 1.0, 1.0]
    runs = {"fast": {"a": [10, 20, 30, 40], "b": [50, 50, 60, None]},
            "slow": {"a": [40, 50, 60, None], "b": [None] * 4}}
    r = ranking(runs, {"a": 100, "b": 200}, {"a": "uniform", "b": "uniform"})
    u = r["protocols"]["uniform"]
    assert u["order"] == ["fast", "slow"] and u["maps"] == ["a", "b"]
    assert u["iqm"]["fast"][1] <= u["iqm"]["fast"][0] <= u["iqm"]["fast"][2]
    p, q = u["poi"]["fast"]["slow"][0], u["poi"]["slow"]["fast"][0]
    assert p > 0.5 and p + q == pytest.approx(1.0)
    assert r["winners"]["a"]["method"] == "fast" and r["winners"]["a"]["median"] == 25.0
    assert r["winners"]["b"] == {"method": "fast", "optimal": 3, "seeds": 4, "median": 55.0,
                                 "ci": r["winners"]["b"]["ci"]}
    import numpy as np
    assert profile([0.1, 0.5, 1.0], np.array([0.0, 0.2, 1.0])).tolist() == [0.0, 1 / 3, 2 / 3]


def test_a_bad_artifact_name_is_refused_before_any_run(tmp_path):
    with pytest.raises(SystemExit) as exc:
        heldout.main(["--out", str(tmp_path / "h"), "--artifact", "Not A Name"])
    assert exc.value.code == 2 and not (tmp_path / "h").exists()


def test_the_diagnosis_says_where_an_untrained_test_from_s_hits_a_wall(tmp_path):
    """After one episode from elsewhere the test from S walks cells never acted in and
    stops at the first wall the model did not know: the diagnosis names the cell, says
    nothing of the walk was acted in, and that the move taken was a wall."""
    import numpy as np

    from learning import RNHQLPlus, train_tabular
    from scenarios.runs.spec import load
    from scenarios.studies.maps.test_from_s import describe, where_it_stops

    assert where_it_stops([5, 4, 3, 3], np.array([0, 0, 0, 1, 2, 3])) == 2
    toml, route, _ = heldout.write_problem("rooms-64", 0.0, 7, 0.0, tmp_path)
    _, model = load(str(toml), rewards="goal-only", s_starts=0.0)
    r = train_tabular(RNHQLPlus(), model, 1, np.random.default_rng(0))
    line = describe(0, r, model, r.state)
    assert f"(optimum {route})" in line and "test no G" in line, line
    assert "a cell never acted in" in line and "the test's move a wall" in line, line
    walked = int(line.split("stops ")[1].split(" moves")[0]) + 1
    assert f"0/{walked} cells of the walk acted in" in line, line


def test_the_diagnosis_renders_its_lines_as_one_block():
    from scenarios.artifacts.tables import KINDS

    text = KINDS["test-from-s"].render({"lines": ["rooms-64@uniform ...", "seed 0: test 92"]})
    assert text == "```text\nrooms-64@uniform ...\nseed 0: test 92\n```\n"


def test_the_finding_across_studies_names_each_map_kinds_winner():
    """The README's finding: a row per study and protocol, a column per map kind, each
    cell the map's winner with its interval, and the lowest IQM of the row."""
    from scenarios.artifacts.tables import KINDS
    from scenarios.studies.maps.ranking import ranking

    def study(size):
        cols = [f"maze-w4-{size} s10 (route 9)", f"rooms-{size} s10 (route 9)",
                f"maze-w4-{size} uniform (route 9)"]
        runs = {"a": {c: [10, 20, None] for c in cols}, "b": {c: [30, 30, 30] for c in cols}}
        protocols = {c: c.split(" ")[1] for c in cols}
        return {"columns": cols, "runs": runs,
                "ranking": ranking(runs, dict.fromkeys(cols, 100), protocols)}

    text = KINDS["heldout"].render_rows([study(256), study(512)])
    lines = text.splitlines()
    assert lines[0] == "| maps | starts | maze-w4 | rooms | lowest IQM [95 %] |"
    assert len(lines) == 2 + 4  # two studies x two protocols
    assert lines[2].startswith("| 256² | 10 % of starts from S | a 2/3 · 20 [")
    assert "| – |" in lines[3]  # no rooms map under uniform starts


def test_a_tie_is_every_tied_method_named_whatever_the_order_they_ran_in():
    """Two methods with the same median and optimal seeds on a map: the table, the finding
    and its words name both, in name order, with the shared figures, and render the same
    when the methods were run (and stored) the other way round."""
    from scenarios.artifacts.heldout import heldout_summary
    from scenarios.artifacts.tables import KINDS
    from scenarios.studies.maps.ranking import ranking

    cols = ["maze-w4-256 uniform (route 9)", "rooms-256 uniform (route 9)"]
    eps = {"zeta": {cols[0]: [20, 30, 40], cols[1]: [10, 10, 10]},
           "alpha": {cols[0]: [25, 30, 35], cols[1]: [50, 60, None]}}

    def study(order):
        runs = {m: eps[m] for m in order}
        protocols = dict.fromkeys(cols, "uniform")
        return {"caption": "c", "columns": cols, "rows": {m: {} for m in order},
                "runs": runs, "budgets": dict.fromkeys(cols, 100), "protocols": protocols,
                "ranking": ranking(runs, dict.fromkeys(cols, 100), protocols)}

    a, b = study(["zeta", "alpha"]), study(["alpha", "zeta"])
    assert a["ranking"]["winners"][cols[0]]["method"] != \
        b["ranking"]["winners"][cols[0]]["method"]  # the study stores the first it ran
    for render in (lambda d: KINDS["heldout"].render(d).split("Per map")[1],  # (rows: as run)
                   lambda d: KINDS["heldout"].render_rows([d]), lambda d: heldout_summary([d])):
        assert render(a) == render(b)
    words = heldout_summary([a])
    assert "`zeta` first on 2 of 2 (maze-w4, rooms)" in words
    assert "`alpha` first on 1 of 2 (maze-w4)" in words
    row = KINDS["heldout"].render_rows([a]).splitlines()[2]
    assert "| alpha = zeta 3/3 · 30 (a tie) |" in row


def test_the_corners_scenario_runs_in_the_held_out_study_from_corner_to_corner(tmp_path):
    """scenarios.studies.maps.corners writes a map's corner-to-corner scenario (its map beside
    it, named relative to it); the held-out study runs it as it is; a bad map exits 2."""
    from scenarios.runs.spec import load
    from scenarios.studies.maps import corners
    from sim.grid.planning import corner_start_goal

    toml, route = corners.write_corners("maze-w2-24", 5, 0.0, tmp_path / "maps")
    free, _ = heldout.problem_map("maze-w2-24", 5, 0.0)
    assert route == corner_start_goal(free)[2]
    _, model = load(str(toml))
    assert int(model.distance_to_goal[model.start]) == route
    assert f'map = "{toml.stem.removesuffix("-corners")}.map"' in toml.read_text()
    out = tmp_path / "h"
    assert heldout.main(["--out", str(out), "--problems", f"{toml}@uniform",
                         "--methods", "haql", "--seeds", "1"]) == 0
    assert f"(route {route})" in (out / "heldout.md").read_text()
    with pytest.raises(SystemExit) as e:
        corners.main(["--maps", "forest-24", "--out", str(tmp_path / "x")])
    assert e.value.code == 2


def test_the_growth_study_tables_episodes_against_free_cells(tmp_path, capsys):
    """scenarios.studies.maps.growth: a row per size with its free cells and route, each
    method's quartiles (never where the median seed never got there), the exponents and
    the N log N yardstick's; bad sizes exit 2."""
    from scenarios.studies.maps import growth

    out = tmp_path / "g"
    assert growth.main(["--out", str(out), "--kind", "open", "--sizes", "24,16",
                        "--methods", "rnh-ql+explore,haql", "--seeds", "2"]) == 0
    text = (out / "growth.md").read_text()
    assert text in capsys.readouterr().out
    rows = [line for line in text.splitlines() if line.startswith("| 16 ") or
            line.startswith("| 24 ")]
    assert [r.split(" | ")[0] for r in rows] == ["| 16", "| 24"]  # sorted by size
    assert all(r.count("/2 · ") == 2 for r in rows)
    assert "Exponents" in text and "N log N grows as N^" in text
    assert growth.quartiles([10, None, 30, 20]) == [17.5, 25.0, None]
    assert growth.exponent([100, 400], [10.0, 40.0]) == pytest.approx(1.0)
    assert growth.exponent([100, 400], [10.0, None]) is None
    for bad in (["--sizes", "4"], ["--kind", "forest"], ["--protocol", "half"],
                ["--kind", "rooms", "--sizes", "16"]):  # rooms of 15 cells: none free
        with pytest.raises(SystemExit) as e:
            growth.main(["--out", str(tmp_path / "x"), *bad])
        assert e.value.code == 2


def test_the_fresh_sets_verdicts_are_read_map_by_map_from_the_artifact():
    """fresh_verdicts: the Q-choosing learner's seeds under uniform starts, the best method
    against the best reference (1.2 x + 10) on every map, the open maps' best method; a
    corner scenario's path is shown as its map and placement."""
    from scenarios.artifacts.heldout import fresh_verdicts, label, map_of
    from scenarios.artifacts.tables import KINDS
    from scenarios.studies.maps.ranking import ranking

    corner = "results/fresh-maps/maze-w4-256-s2027-b0.02-corners.toml uniform (route 9)"
    cols = ["open-256 uniform (route 9)", corner, "open-256 s10 (route 9)"]
    runs = {"mine": {cols[0]: [10] * 9 + [None], cols[1]: [50] * 8 + [None] * 2,
                     cols[2]: [40] * 10},
            "r-max": {cols[0]: [20] * 10, cols[1]: [30] * 10, cols[2]: [30] * 10},
            "haql": {cols[0]: [None] * 10, cols[1]: [None] * 10, cols[2]: [10] * 10}}
    protocols = {c: c.split(" ")[1] for c in cols}
    d = {"caption": "c", "columns": cols, "rows": {m: {} for m in runs}, "runs": runs,
         "budgets": dict.fromkeys(cols, 100), "protocols": protocols,
         "ranking": ranking(runs, dict.fromkeys(cols, 100), protocols)}
    text = fresh_verdicts(d, "mine")
    assert "under uniform starts: missed on 1 of 2 (maze-w4-256 corners uniform 8/10)" in text
    assert "(r-max): met on 3 of 3 maps" in text  # mine 10 vs 20; r-max 30 wins; haql 10
    assert "open-256 uniform mine 9/10; open-256 s10 haql 10/10" in text
    assert map_of(corner) == ("maze-w4 corners", "256")
    assert label(corner) == "maze-w4-256 corners uniform (route 9)"
    assert "| maze-w4-256 corners uniform (route 9) |" in KINDS["heldout"].render(d)
    assert "(other was not run here.)" in fresh_verdicts(d, "other")
    from scenarios.artifacts.heldout import head_to_head

    h2h = head_to_head(d, "mine", "r-max")
    assert "**uniform starts**: P(`mine` < `r-max`) " in h2h
    assert "open 10 against 20 (0.5 ×); maze-w4 corners 50 against 30 (1.7 ×)." in h2h
    assert "**10 % of starts from S**: P(`mine` < `r-max`) 0.00" in h2h
    assert "open 40 against 30 (1.3 ×)." in h2h


def test_run_times_names_the_fastest_and_slowest_map_and_counts_those_within_the_limit():
    from scenarios.artifacts.heldout import run_times

    d = {"rows": {"r-max": {"caves-512 s10 (route 998)": "10/10 · 85 · 12.5 s",
                            "maze-w4-512 uniform (route 3644)": "10/10 · 90 · 71.0 s",
                            "rooms-512 s10 (route 988)": "9/10 · 60 · 8 s"}}}
    text = run_times(d, "r-max", 60)
    assert text == ("`r-max`, median wall time per run: 8 s (rooms-512 s10) to 71 s "
                    "(maze-w4-512 uniform); within 60 s on 2 of 3 maps.\n")
    assert "no timed runs" in run_times(d, "haql", 60)
    assert run_times(d, "r-max").endswith("71 s (maze-w4-512 uniform).\n")


def test_a_sweep_keeping_the_summarys_fields_draws_no_figures(tmp_path):
    from scenarios.sweep import kept

    with pytest.raises(ValueError, match="draws no figures"):
        kept.run_sweep([], tmp_path, run_local, figures=True)


def test_kept_records_give_a_physics_sweep_the_same_summary_as_whole_ones(tmp_path):
    from scenarios.runs.results import summarise, summary_markdown
    from scenarios.sweep.kept import kept
    from scenarios.sweep.run import assemble

    specs = make_specs("paper-40", ["st-ql"], [0, 1], 5, ["grid", "physics"],
                       rewards="goal-only")
    whole = run_sweep(specs, tmp_path / "whole", run_local, figures=False, progress=None)
    runs = whole["runs"]
    assert all("final_policy" in kept(r) for r in runs if r["world"] == "physics")
    assert summarise([kept(r) for r in runs]) == summarise(runs)
    assert "robot seconds" in summary_markdown(whole)
    assert summary_markdown(assemble(specs, [kept(r) for r in runs])) == summary_markdown(whole)
