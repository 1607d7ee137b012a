from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from scenarios.cli import main
from tests.conftest import MAPS


def test_scenarios_lists_builtins_with_optimal_lengths(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    for name in ("paper-40", "paper-50", "zigzag-50", "arena"):
        assert name in out
    line = next(line for line in out.splitlines() if line.startswith("paper-50"))
    assert "2500" not in line and " 80 " in line


def test_check_a_good_map(capsys):
    assert main(["scenarios", "--check", str(MAPS / "arena.map"), "--start", "3,43",
                 "--goal", "45,5"]) == 0
    assert "OK" in capsys.readouterr().out


ARENA = str(MAPS / "arena.map")  # what the word ARENA stands for in a command below


@pytest.mark.parametrize(("command", "words"), [
    ("scenarios --check missing.toml", "does not exist"),
    ("scenarios --check ARENA", "needs a start and a goal"),
    ("scenarios --check ARENA --start 3;43 --goal 1,1", "expected X,Y"),
    ("scenarios --check ARENA --start 0,0 --goal 45,5", "blocked"),
    ("train paper-40 --s-starts 1", "--s-starts: must be in [0, 1)"),
    ("train paper-40 --rewards foo", "paper, goal-only, step-cost, scenario"),
    ("compare paper-40 --s-starts -0.5 --out x", "--s-starts: must be in"),
    ("train paper-40 --method sarsa-xx", "unknown method"),
    ("train paper-40 --set alpha", "FIELD=NUMBER"),
    ("train paper-40 --set colour=1", "has no field"),
    ("train paper-40 --set alpha=7", "alpha"),
    ("train paper-40 --world moon", "--world: is 'moon', not a world"),
    ("train paper-40 --episodes 0", "must be >= 1"),
    ("train paper-40 --save /nonexistent/dir/a.npz --episodes 1", "cannot write"),
    ("compare paper-40 --methods st-ql,nope --out x", "unknown method"),
    ("route paper-40 --agent missing.npz", "no such checkpoint"),
    ("train paper-40 --seed -1", "--seed: must be >= 0"),
    ("train paper-40 --episodes 1000000000000", "more than the limit"),
    ("train paper-40 --index 3", "--index: only applies with --scen"),
    ("compare paper-40 --seeds 1000000000 --out x", "more than the limit"),
    ("compare paper-40 --seed-base -1 --out x", "--seed-base: must be >= 0"),
    ("compare paper-40 --jobs 0 --out x", "--jobs: must be >= 1"),
    ("compare paper-40 --jobs -3 --out x", "--jobs: must be >= 1"),
    ("compare paper-40 --methods st-ql,st-ql --out x", "names 'st-ql' twice"),
    ("compare paper-40 --methods dyna-q --set n_planning=2.5 --out x", "is a whole number"),
    ("compare paper-40 --address auto --out x", "--address: only applies with the Ray backend"),
    ("compare paper-40 --backend moon --out x", "Fix: pass --backend local or --backend ray"),
    ("compare paper-40 --world grid,moon --out x", "--world: has 'moon'"),
    ("train paper-40 --json .", "--json: . is a directory"),
    ("route paper-40 --agent a.npz --png d", "does not end in .png"),
    ("optimum paper-40 --fidelity noisy,speed=2", "speed: is not a fidelity knob"),
    ("optimum paper-40 --samples 0", "--samples: must be >= 1"),
    ("optimum paper-40 --seed -1", "--seed: must be >= 0"),
    ("optimum paper-40 --rollouts -2", "--rollouts: must be >= 1"),
    ("optimum no-such-map", "is not a named scenario"),
])
def test_bad_input_prints_one_line_and_exits_2(capsys, command, words):
    argv = [ARENA if a == "ARENA" else a for a in command.split()]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and err.count("\n") == 1


def test_train_save_route_and_resume(tmp_path, capsys):
    a, b, c = (tmp_path / f"{n}.npz" for n in "abc")
    assert main(["train", "paper-40", "--method", "rnh-ql", "--episodes", "30", "--save",
                 str(a), "--json", str(tmp_path / "a.json")]) == 0
    assert main(["train", "paper-40", "--method", "rnh-ql", "--episodes", "60",
                 "--resume", str(a), "--save", str(b), "--json", str(tmp_path / "b.json")]) == 0
    assert main(["train", "paper-40", "--method", "rnh-ql", "--episodes", "60", "--save",
                 str(c), "--json", str(tmp_path / "c.json")]) == 0
    import json

    resumed, straight = (json.loads((tmp_path / f"{n}.json").read_text()) for n in "bc")
    assert resumed["steps_per_episode"] == straight["steps_per_episode"]
    capsys.readouterr()
    assert main(["route", "paper-40", "--agent", str(b), "--png", str(tmp_path / "r.png")]) == 0
    out = capsys.readouterr().out
    assert "BFS optimum: 60 moves" in out and "S" in out and (tmp_path / "r.png").exists()


def test_corrupt_checkpoint_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 not really a zip")
    assert main(["route", "paper-40", "--agent", str(bad)]) == 2
    assert "corrupt" in capsys.readouterr().err


def test_console_script_exit_code(tmp_path):
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "scenarios.cli", "scenarios", "--check",
                           str(tmp_path / "none.toml")], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1


def test_set_applies_to_the_methods_that_have_the_field(tmp_path):
    out = tmp_path / "o"
    assert main(["compare", "paper-40", "--methods", "st-ql,rnh-ql", "--seeds", "1",
                 "--episodes", "10", "--set", "k=20", "--out", str(out), "--jobs", "1"]) == 0
    runs = json.loads((out / "results.json").read_text())["runs"]
    assert {r["method"]: r["config"].get("k") for r in runs} == {"st-ql": None, "rnh-ql": 20}


def test_set_with_a_field_no_method_has_is_an_input_error(tmp_path, capsys):
    assert main(["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes",
                 "10", "--set", "k=20", "--out", str(tmp_path / "o")]) == 2
    assert "none of the methods" in capsys.readouterr().err


def test_out_that_is_a_file_is_an_input_error(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes",
                 "10", "--out", str(f)]) == 2
    err = capsys.readouterr().err
    assert str(f) in err and "not a directory" in err and err.count("\n") == 1


def test_out_in_use_by_a_live_sweep_is_refused_and_a_stale_lock_taken_over(tmp_path, capsys):
    from scenarios.sweep.outdir import LOCK_NAME

    out = tmp_path / "o"
    out.mkdir()
    lock = out / LOCK_NAME
    # a live holder of the kernel lock, as a running sweep holds it
    holder = subprocess.Popen([sys.executable, "-c", (
        "import fcntl, os, sys, time\n"
        f"fd = os.open({str(lock)!r}, os.O_RDWR | os.O_CREAT)\n"
        "fcntl.flock(fd, fcntl.LOCK_EX)\n"
        "os.pwrite(fd, f'{os.getpid()}\\n'.encode(), 0)\n"
        "print('held', flush=True)\n"
        "time.sleep(60)\n")], stdout=subprocess.PIPE, text=True)
    args = ["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes",
            "10", "--out", str(out)]
    try:
        assert holder.stdout.readline().strip() == "held"
        assert main(args) == 2
        assert f"in use by another sweep (pid {holder.pid})" in capsys.readouterr().err
    finally:
        holder.kill()
        holder.wait()
    assert main(args) == 0  # its owner is gone: the lock is stale
    assert not lock.exists()


def test_a_lock_file_naming_a_live_process_that_holds_no_lock_does_not_block(tmp_path):
    """Only the kernel lock decides: a lock file naming pid 1 (planted, or left by a
    sweep whose pid was reused) must not block a shared folder forever."""
    from scenarios.sweep.outdir import LOCK_NAME

    out = tmp_path / "o"
    out.mkdir()
    (out / LOCK_NAME).write_text("1\n")
    assert main(["compare", "paper-40", "--methods", "st-ql", "--seeds", "1", "--episodes",
                 "10", "--out", str(out)]) == 0
    assert not (out / LOCK_NAME).exists()


def test_scen_problem_sets_map_start_and_goal(capsys):
    scen = str(MAPS / "arena.map.scen")
    assert main(["scenarios", "--scen", scen, "--index", "0"]) == 0
    out = capsys.readouterr().out
    # problem 0 of arena.map.scen: (19, 26) -> (19, 29) in the Moving AI frame (y down),
    # i.e. cells (19, 22) -> (19, 19) in rnhql's frame (y up) on a 49-row map
    assert "(19, 26) -> (19, 29)" in out and "(19, 22)" in out and "(19, 19)" in out


def test_scen_errors_are_one_line(capsys, tmp_path):
    scen = str(MAPS / "arena.map.scen")
    for args, words in ((["--index", "999"], "out of range"), ([], "exactly one of"),
                        (["--bucket", "99"], "no problem in bucket")):
        assert main(["scenarios", "--scen", scen, *args]) == 2
        err = capsys.readouterr().err
        assert words in err and err.count("\n") == 1
    assert main(["train", "paper-40", "--scen", scen, "--index", "0"]) == 2
    assert "drop the scenario argument" in capsys.readouterr().err


def test_a_scenario_name_never_sends_the_default_recording_out_of_recordings(tmp_path,
                                                                             monkeypatch):
    from scenarios.sweep.outdir import record_path

    monkeypatch.chdir(tmp_path)
    args = type("A", (), {"record": ""})()
    for name in ("../../escaped", "/abs/olute", ".hidden"):
        path = Path(record_path(args, name, "st-ql-grid-s0")).resolve()
        assert path.parent == (tmp_path / "recordings").resolve(), name


def test_resume_with_other_rewards_is_refused(tmp_path, capsys):
    ck = str(tmp_path / "a.npz")
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "10",
                 "--save", ck]) == 0
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "20", "--resume", ck,
                 "--rewards", "paper"]) == 2
    assert "field 'problem.rewards'" in capsys.readouterr().err
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "20",
                 "--resume", ck]) == 0


def test_train_defaults_to_goal_only_and_says_how_to_get_the_papers_rewards(capsys):
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "5"]) == 0
    out = capsys.readouterr().out
    assert "rewards goal-only" in out and "--rewards paper" in out
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "5",
                 "--rewards", "scenario"]) == 0  # the file's own: the built-ins' paper rewards
    out = capsys.readouterr().out
    assert "rewards paper" in out and "--rewards paper" not in out


def test_scen_rows_that_do_not_fit_their_map_are_refused(tmp_path, capsys):
    import shutil

    shutil.copy(Path(__file__).parent.parent / "sim/builtin/maps/arena.map", tmp_path)
    size = tmp_path / "size.scen"
    size.write_text("version 1\n0\tarena.map\t50\t49\t19\t26\t19\t29\t3.0\n")
    assert main(["train", "--scen", str(size), "--index", "0", "--episodes", "2"]) == 2
    assert "50x49 but arena.map is 49x49" in capsys.readouterr().err
    escape = tmp_path / "pw.scen"
    escape.write_text("version 1\n0\t../../../../etc/passwd\t49\t49\t19\t26\t19\t29\t3.0\n")
    assert main(["train", "--scen", str(escape), "--index", "0", "--episodes", "2"]) == 2
    assert "not a .map file beside the .scen" in capsys.readouterr().err


def test_view_without_a_display_suggests_the_web_viewer(tmp_path, monkeypatch, capsys):
    import sys

    if not sys.platform.startswith("linux"):
        pytest.skip("display detection is for Linux")
    rrd = tmp_path / "x.rrd"
    rrd.write_bytes(b"RRF2 not opened")  # starts as an .rrd does
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", str(rrd)]) == 2
    err = capsys.readouterr().err
    assert "no display" in err and f"rnhql view {rrd} --web" in err


def test_single_run_output_says_never_without_a_unit(capsys):
    from scenarios.cli.train import print_run

    print_run({"episodes_to_stable_optimal": None, "episodes_to_optimal": None,
               "final_route_length": -1, "success_rate": 0.0, "optimal_action_fraction": 0.5,
               "env_steps": 10, "wall_time_s": 0.1}, 80)
    out = capsys.readouterr().out
    assert "never episodes" not in out and "stable optimal after  never" in out


def test_every_flag_of_every_command_has_a_help_line_and_its_default():
    import argparse

    from scenarios.cli.app import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        text = p.format_help()
        for act in p._actions:
            if isinstance(act, argparse._HelpAction):
                continue
            assert act.help, f"rnhql {name} {act.dest}: no help line"
            d = act.default
            if act.option_strings and d not in (None, False, argparse.SUPPRESS):
                assert "default" in p._get_formatter()._get_help_string(act), (name, act.dest)
        assert "--help" in text


def test_optimum_prints_v_star_next_to_the_exact_and_continuous_optima(capsys):
    from sim.physics.models.build import stochastic_model

    stochastic_model.cache_clear()
    assert main(["optimum", "paper-40", "--rollouts", "2"]) == 0
    out = capsys.readouterr().out
    assert "paper-40 at fidelity exact" in out and "1,388 states: 1,388 arrived" in out
    assert "5,552 primitives driven in" in out
    for line in ("V*(S)       60.00 expected primitives", "P(G)        1.0000 within the "
                 "episode's 600 primitives", "exact       60 primitives", "continuous  43.3 m",
                 "2 rollouts of the optimal policy: P(G) 1.0000"):
        assert line in out, line
    stochastic_model.cache_clear()
    assert main(["optimum", "paper-40"]) == 0  # a new process: from the disk cache
    assert "loaded from the cache" in capsys.readouterr().out
    stochastic_model.cache_clear()


def test_version_prints_the_installed_version(capsys):
    with pytest.raises(SystemExit) as err:
        main(["--version"])
    assert err.value.code == 0
    assert capsys.readouterr().out.startswith("rnhql ")


def test_train_defaults_to_a_method_that_learns_the_route(capsys):
    assert main(["train", "paper-40", "--episodes", "200"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("RNH-QL+ on paper-40")
    assert "this tool's default (the paper's own scheme is --rewards paper)" in out
    assert "G not reached" not in out


def test_ablation_target_scales_with_the_seeds():
    from scenarios.studies.maps.ablation import target_seeds

    assert [target_seeds(n) for n in (1, 3, 5, 10, 20)] == [1, 3, 5, 9, 18]


def test_fidelity_on_a_grid_only_run_is_an_error_not_ignored(capsys):
    assert main(["train", "paper-40", "--fidelity", "noisy", "--episodes", "2"]) == 2
    assert "applies to the physics world only" in capsys.readouterr().err


def test_physics_train_names_its_fidelity(capsys):
    assert main(["train", "paper-40", "--world", "physics", "--fidelity", "noisy",
                 "--episodes", "2"]) == 0
    assert "(physics at fidelity noisy)" in capsys.readouterr().out


def test_a_missing_scenario_path_folder_is_an_error(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("RNHQL_SCENARIO_PATH", str(tmp_path / "nope"))
    assert main(["scenarios"]) == 2
    assert "no such folder" in capsys.readouterr().err


def test_scenario_list_keeps_circles_and_blocked_cells_apart(capsys):
    assert main(["scenarios"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert "circles" in head and "blocked map cells" in head


def test_subcommand_help_lists_the_methods_and_examples(capsys):
    from learning.methods.registry import comparison_methods

    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    out = capsys.readouterr().out
    assert all(m in out for m in comparison_methods()) and "examples:" in out


def test_a_copied_scenario_under_a_new_file_name_says_so(capsys, monkeypatch, tmp_path):
    from sim.scenario_io import named_scenario_path

    (tmp_path / "mine.toml").write_text(named_scenario_path("paper-50").read_text())
    monkeypatch.setenv("RNHQL_SCENARIO_PATH", str(tmp_path))
    assert main(["train", "mine", "--episodes", "2"]) == 2
    err = capsys.readouterr().err
    assert "mine.toml: name: is 'paper-50'" in err and 'set name = "mine"' in err


def test_the_default_recording_keeps_the_method_name_the_docs_print(tmp_path, monkeypatch):
    """docs/usage.md's tour opens recordings/paper-50-rnh-ql+-grid-s0.rrd: the file a
    default --record of rnh-ql+ writes (it was rnh-ql_)."""
    from scenarios.sweep.outdir import RECORD_DEFAULT, record_path

    monkeypatch.chdir(tmp_path)
    args = type("A", (), {"record": RECORD_DEFAULT})()
    assert record_path(args, "paper-50", "rnh-ql+-grid-s0") == \
        "recordings/paper-50-rnh-ql+-grid-s0.rrd"


def test_compare_prints_a_summary_that_fits_100_columns(tmp_path, capsys):
    """The terminal gets a compact table and the verdict's headlines (summary.md the rest),
    every line within 100 columns, long method names included."""
    from scenarios.cli import main

    assert main(["compare", "paper-40", "--methods",
                 "rnh-ql,st-ql,tests.plain_learners.st_ql:STQLPort", "--world", "grid,physics",
                 "--seeds", "2", "--episodes", "10", "--jobs", "1", "--out",
                 str(tmp_path / "c")]) == 0
    out = capsys.readouterr().out
    assert max(len(line) for line in out.splitlines()) <= 100
    assert "stable optimal after: median [95 % CI]" in out and "P(G)" in out
    assert "- grid: " in out and "- physics: " in out
    flat = " ".join(out.split())
    assert "full tables and the pairwise verdicts: " in flat
    assert "  - rnh-ql vs" not in out  # those: summary.md
    assert "  - RNH-QL vs st-ql" in (tmp_path / "c" / "summary.md").read_text() or \
        "  - RNH-QL vs " in (tmp_path / "c" / "summary.md").read_text()


def test_a_first_physics_run_says_it_compiles(tmp_path):
    """On a cold cache train --world physics says what it compiles before the silence; on a
    warm one it says nothing."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    argv = [sys.executable, "-m", "scenarios.cli", "train", "paper-40", "--method", "st-ql",
            "--world", "physics", "--episodes", "1"]
    cold = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=600)
    assert cold.returncode == 0, cold.stderr[-2000:]
    assert "compiling the numba kernels of 1 method and the physics world's kernels" in \
        cold.stderr
    warm = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=600)
    assert warm.returncode == 0 and "compiling" not in warm.stderr


def test_a_method_typo_gets_a_did_you_mean(capsys):
    from scenarios.cli import main

    assert main(["train", "paper-40", "--method", "rnhql+", "--episodes", "2"]) == 2
    assert "did you mean rnh-ql+" in capsys.readouterr().err


def test_train_resume_says_where_it_resumes_from(tmp_path, capsys):
    from scenarios.cli import main

    agent = str(tmp_path / "a.npz")
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "20",
                 "--save", agent]) == 0
    capsys.readouterr()
    assert main(["train", "paper-40", "--method", "st-ql", "--episodes", "30",
                 "--resume", agent]) == 0
    assert f"resuming {agent}: 20 of 30 episodes done, training the other 10" in \
        capsys.readouterr().out


def test_a_silent_command_says_it_still_works_and_a_viewer_does_not(monkeypatch, capsys):
    """Whatever a command does, it never stays silent past QUIET_S: a line says it still
    works, and any output resets the clock; a viewer (served until Ctrl-C) is left alone."""
    import time

    from scenarios.cli import app

    monkeypatch.setattr(app, "QUIET_S", 0.3)
    beat = app._Heartbeat()
    time.sleep(1.0)
    beat.stop()
    err = capsys.readouterr().err
    assert "… still working" in err
    quiet = app._Heartbeat(enabled=False)
    time.sleep(0.6)
    quiet.stop()
    assert capsys.readouterr().err == ""
    assert "view" in app.NO_HEARTBEAT
