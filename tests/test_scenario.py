from __future__ import annotations

import dataclasses
import re
import textwrap

import numpy as np
import pytest

from sim.errors import ScenarioError
from sim.feasibility import validate
from sim.maps.layouts import random_circles
from sim.scenario import Circle, Robot, Scenario
from sim.scenario_io import builtin_names, load_scenario, resolve_scenario
from tests.conftest import MAPS, REPO

REPO_BUILTIN = REPO / "sim" / "builtin"

BASE = """\
name = "t"
start = [1, 1]
goal = [8, 8]
[arena]
width_m = 10.0
height_m = 10.0
"""


def write(tmp_path, body, name="s.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(body))
    return p


def test_builtins_load_and_include_a_long_detour():
    names = builtin_names()
    assert {"paper-40", "paper-50", "arena", "zigzag-50"} <= set(names)
    sc = resolve_scenario("paper-50")
    assert (sc.nx, sc.ny, sc.start, sc.goal) == (50, 50, (5, 5), (45, 45))
    assert resolve_scenario("paper-40").goal == (35, 35)


def test_random_layout_is_deterministic_and_keeps_start_goal_connected():
    sc = Scenario(name="r", width_m=30, height_m=30, start=(3, 3), goal=(26, 26))
    a = random_circles(sc, 15, 1.0, 2.5, np.random.default_rng(7))
    b = random_circles(sc, 15, 1.0, 2.5, np.random.default_rng(7))
    assert a == b and len(a) == 15
    validate(dataclasses.replace(sc, obstacles=a))  # connected, start/goal free


def test_good_toml_loads(tmp_path):
    sc = load_scenario(write(tmp_path, BASE + "[obstacles]\ncircles = [[5.0, 5.0, 1.0]]\n"))
    assert sc.obstacles == (Circle(5.0, 5.0, 1.0),)


def test_toml_may_reference_a_map(tmp_path):
    (tmp_path / "m.map").write_text((MAPS / "arena.map").read_text())
    sc = load_scenario(write(tmp_path, 'start = [3, 5]\ngoal = [45, 43]\n[arena]\nmap = "m.map"\n'))
    assert (sc.nx, sc.ny) == (49, 49) and len(sc.blocked_cells) > 0


BAD = [
    ("colour = 'red'\n" + BASE, "colour", "unknown key"),
    (BASE + "depth_m = 3.0\n", "arena.depth_m", "unknown key"),
    (BASE + "[robot]\nwheels = 3\n", "robot.wheels", "unknown key"),
    (BASE.replace("[1, 1]", "[5, 5]") + "[obstacles]\ncircles = [[5.5, 5.5, 1.0]]\n",
     "start", "blocked"),
    (BASE.replace("[1, 1]", "[12, 1]"), "start", "outside"),
    (BASE.replace("[8, 8]", "[-1, 8]"), "goal", "outside"),
    (BASE + "[obstacles]\ncircles = [[7.0, 7.0, 3.3]]\n", "goal", "blocked"),
    (BASE + "[[obstacles.chains]]\nfrom = [0.0, 5.0]\nto = [10.0, 5.0]\nradius_m = 0.6\n",
     "goal", "cannot be reached"),
    (BASE + "[obstacles]\ncircles = [[5.0, 5.0, -1.0]]\n", "obstacles.circles[0]", "radius"),
    (BASE + "[obstacles]\ncircles = [[5.0, 5.0, nan]]\n", "obstacles.circles[0]", "radius"),
    (BASE.replace("width_m = 10.0", "width_m = 10.0\ncell_size_m = 3.0"), "arena.width_m",
     "whole number"),
    (BASE + "[robot]\nradius_m = 0.6\n", "robot.radius_m", "does not fit"),
    (BASE + "[robot]\nradius_m = -0.3\n", "robot.radius_m", "positive"),
    (BASE.replace('start = [1, 1]', 'start = "a"'), "start", "expected list"),
    ("steps_per_episode = 0\n" + BASE, "steps_per_episode", "integer in 1.."),
    ("steps_per_episode = 100000000000000\n" + BASE, "steps_per_episode", "integer in 1.."),
    (BASE.replace("width_m = 10.0", "width_m = 1e7"), "arena.width_m", "more than the limit"),
    (BASE + "[obstacles.random]\ncount = 100000\nradius_min_m = 0.5\nradius_max_m = 1.0\n"
     "seed = 1\n", "obstacles.random.count", "cannot leave a route"),
    (BASE + "[obstacles]\ncircles = [[1.5, 1.5, 0.5]]\n[obstacles.random]\ncount = 3\n"
     "radius_min_m = 0.5\nradius_max_m = 1.0\nseed = 1\n", "start", "blocked"),
    ("name = \n", "TOML", "cannot be parsed"),
    ("s_start_share = 1.0\n" + BASE, "s_start_share", "in [0, 1)"),
    ("s_start_share = -0.1\n" + BASE, "s_start_share", "in [0, 1)"),
]


@pytest.mark.parametrize(("body", "field", "words"), BAD)
def test_bad_scenarios_name_file_field_and_fix(tmp_path, body, field, words):
    path = write(tmp_path, body)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    err = info.value
    assert err.source == str(path)
    assert err.field == field, str(err)
    assert words in str(err)
    assert "Fix: " in str(err) and err.fix


def test_bad_map_files_raise_through_the_scenario_loader(tmp_path):
    (tmp_path / "m.map").write_text("type octile\nheight 2\nwidth 3\nmap\n...\n..?\n")
    with pytest.raises(ScenarioError, match="unknown map character"):
        load_scenario(write(tmp_path, 'start = [0, 0]\ngoal = [2, 1]\n[arena]\nmap = "m.map"\n'))


def test_unknown_name_lists_the_builtins():
    with pytest.raises(ScenarioError, match="paper-50"):
        resolve_scenario("paper-51")


def test_map_start_goal_use_the_movingai_frame():
    sc = resolve_scenario(str(MAPS / "arena.map"), (3, 43), (45, 5))
    assert sc.start == (3, 5) and sc.goal == (45, 43)
    with pytest.raises(ScenarioError) as info:
        resolve_scenario(str(MAPS / "arena.map"), (0, 0), (45, 5))
    assert info.value.field == "--start 0,0"


def test_robot_too_large_for_a_cell_is_a_clear_error():
    sc = Scenario(name="t", width_m=10, height_m=10, start=(1, 1), goal=(8, 8),
                  robot=Robot(radius_m=0.5))
    with pytest.raises(ScenarioError, match="does not fit"):
        validate(sc)


def test_reward_schemes_from_toml_and_text(tmp_path):
    from sim.scenario import Rewards, rewards_from_text

    base = (REPO_BUILTIN / "paper-40.toml").read_text()
    for extra, expected in (("", ("paper", 100, -1, 1)),
                            ('[rewards]\nscheme = "goal-only"\n', ("goal-only", 100, -1, 0)),
                            ('[rewards]\nscheme = "goal-only"\nbump = -2.0\n',
                             ("custom", 100, -2, 0)),
                            ("[rewards]\nstep = -1.0\n", ("step-cost", 100, -1, -1))):
        path = tmp_path / "s.toml"
        path.write_text(base + "\n" + extra)
        rw = load_scenario(path).rewards
        assert (rw.scheme, rw.goal, rw.bump, rw.step) == expected
    path.write_text(base + '\n[rewards]\nscheme = "nope"\n')
    with pytest.raises(ScenarioError, match=r"rewards.scheme.*unknown reward scheme.*goal-only"):
        load_scenario(path)
    assert rewards_from_text("step-cost") == Rewards(100, -1, -1, "step-cost")
    assert rewards_from_text("step=0") == Rewards(100, -1, 0, "goal-only")
    assert rewards_from_text("scheme=step-cost,goal=50").scheme == "custom"
    for bad in ("nope", "step=x", "gaol=1", "step=inf"):
        with pytest.raises(ScenarioError, match="--rewards"):
            rewards_from_text(bad)


def test_rewards_reach_the_model():
    from scenarios.runs.spec import load

    _, paper = load("paper-40")
    _, goal_only = load("paper-40", None, None, "goal-only")
    free = (paper.reward == 1.0)
    assert free.any() and (goal_only.reward[free] == 0.0).all()
    assert (goal_only.reward[paper.reward == 100.0] == 100.0).all()


def test_s_start_share_puts_s_among_the_episode_starts_with_that_probability(tmp_path):
    from sim.grid import build_model

    plain = build_model(load_scenario(write(tmp_path, BASE)))
    mixed = build_model(load_scenario(write(tmp_path, "s_start_share = 0.25\n" + BASE)))
    free = plain.start_states
    assert np.array_equal(mixed.start_states[:len(free)], free)  # the paper's starts, then S
    share = float(np.mean(mixed.start_states == mixed.start))
    assert abs(share - 0.25) < 1.0 / len(mixed.start_states) + 1.0 / len(free)


def test_a_missing_map_names_the_scenario_file_and_its_field(tmp_path):
    from sim.errors import ScenarioError
    from sim.scenario_io import load_scenario

    toml = tmp_path / "t.toml"
    toml.write_text('name = "t"\nstart = [1, 1]\ngoal = [3, 3]\n[arena]\nmap = "nope.map"\n')
    with pytest.raises(ScenarioError, match=r"t\.toml: arena\.map: 'nope\.map' is not a file"):
        load_scenario(toml)


def test_the_example_scenario_is_complete_and_valid(tmp_path, capsys):
    """rnhql scenarios --example prints a file that loads, and names every field a scenario,
    its robot and its rewards have."""
    import dataclasses

    from scenarios.cli import main
    from sim.scenario import Rewards, Robot, Scenario
    from sim.scenario_io import load_scenario

    assert main(["scenarios", "--example"]) == 0
    text = capsys.readouterr().out
    path = tmp_path / "my-arena.toml"
    path.write_text(text)
    sc = load_scenario(path)
    assert sc.name == "my-arena" and sc.physics is not None and len(sc.obstacles) > 2
    for cls in (Scenario, Robot, Rewards):
        for f in dataclasses.fields(cls):
            if f.name in ("source", "obstacles", "blocked_cells", "robot", "rewards", "physics",
                          "width_m", "height_m", "cell_size_m"):
                continue  # tables, or the arena's, or set by the loader
            assert f"{f.name} =" in text or f"{f.name} = " in text, f.name


@pytest.mark.parametrize(("change", "field"), [
    ({"blocked_cells": ((-1, 0),)}, "blocked_cells[0]"),
    ({"blocked_cells": ((3, 3), (10, 3))}, "blocked_cells[1]"),
    ({"blocked_cells": ((3.7, 3),)}, "blocked_cells[0]"),
    ({"start": (1.5, 1)}, "start"),
])
def test_a_python_scenario_gets_the_files_range_checks(change, field):
    """A Scenario built in Python (the API, Gymnasium) is checked as a file's: a negative or
    too large cell would block another cell, a float one would truncate."""
    import dataclasses

    from sim.errors import ScenarioError
    from sim.scenario import Scenario
    from sim.scenario_io import resolve_scenario

    sc = dataclasses.replace(Scenario("t", 10.0, 10.0, (1, 1), (8, 8)), **change)
    with pytest.raises(ScenarioError, match=re.escape(f": {field}: ")):
        resolve_scenario(sc)


def test_random_circles_that_do_not_all_fit_are_an_error_not_fewer_circles(tmp_path):
    from sim.scenario_io import load_scenario

    toml = tmp_path / "few.toml"
    toml.write_text('name = "t"\nstart = [0, 0]\ngoal = [2, 2]\n[arena]\nwidth_m = 3.0\n'
                    'height_m = 3.0\n[obstacles.random]\ncount = 2\nradius_min_m = 0.5\n'
                    'radius_max_m = 1.0\nseed = 1\n')
    with pytest.raises(ScenarioError, match=r"obstacles\.random\.count: only 1 of 2 circles "
                                            r"fit"):
        load_scenario(toml)
