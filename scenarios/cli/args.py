"""Argument helpers shared by the ``rnhql`` subcommands: cells, lists, overrides, limits
(output paths: :mod:`scenarios.sweep.outdir`).

Every helper raises :class:`sim.errors.InputError` (one line naming the flag and
the fix); :mod:`scenarios.cli.app` prints it and exits 2.
"""

from __future__ import annotations

import argparse
import contextlib
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from learning.jitcache import kernels_cached

# the library's limits and defaults, the one definition of each (train, route and compare
# use DEFAULT_REWARDS without --rewards)
from scenarios.api_args import (  # noqa: F401  (re-exported)
    DEFAULT_REWARDS,
    MAX_EPISODES,
    MAX_SEED,
    MAX_SEEDS,
)
from scenarios.runs.spec import (  # noqa: F401  (physics_budget: re-exported)
    MAX_PHYSICS_STEPS_PER_EPISODE,
    WORLDS,
    ExperimentError,
    load,
    physics_budget,
)
from scenarios.sweep.outdir import RECORD_DEFAULT
from sim.errors import InputError
from sim.maps.movingai import load_map, load_scen
from sim.physics.fidelity import Fidelity, parse_fidelity
from sim.physics.jitcache import kernels_cached as physics_cached
from sim.scenario import REWARD_SCHEMES

if TYPE_CHECKING:
    from sim.grid import TabularModel
    from sim.scenario import Cell, Scenario


class CliError(InputError):
    """Bad command-line input that no lower layer can name better."""


def parse_cell(text: str, flag: str) -> tuple[int, int]:
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise CliError("command line", flag, f"expected X,Y integers, got {text!r}",
                       f"write e.g. {flag} 3,5") from None
    return x, y




def add_scenario_args(p: argparse.ArgumentParser, positional: bool = True,
                      learning: bool = False) -> None:
    """The scenario's name or file, S and G, a Moving AI problem, and ``--rewards``.
    ``learning``: a command that trains or grades (train, route, compare), whose rewards
    default to goal-only (see :func:`rewards_arg`)."""
    if positional:
        p.add_argument("scenario", nargs="?",
                       help="built-in name (see `rnhql scenarios`), a .toml, or a .map "
                            "(or give --scen)")
    p.add_argument("--start", help="X,Y start for a .map (Moving AI frame: y counts down)")
    p.add_argument("--goal", help="X,Y goal for a .map (Moving AI frame: y counts down)")
    p.add_argument("--scen", metavar="FILE.scen",
                   help="a Moving AI problem list: its map, start and goal (with --index or "
                        "--bucket)")
    p.add_argument("--index", type=int, metavar="N", help="with --scen: the N-th problem (from 0)")
    p.add_argument("--bucket", type=int, metavar="B",
                   help="with --scen: the last (longest) problem of bucket B")
    own = ("default: goal-only, under which every method's learning shows; 'scenario': the "
           "scenario's own, e.g. the built-ins' paper rewards" if learning
           else "default: the scenario's own")
    p.add_argument("--rewards", metavar="SCHEME",
                   help="reward scheme: paper (+100 goal, -1 bump, +1 free step), goal-only "
                        f"(free step 0), step-cost (free step -1), or goal=..,bump=..,step=.. "
                        f"({own})")
    if learning:
        p.add_argument("--s-starts", metavar="SHARE", type=float, default=None,
                       help="share of training episodes that start at S, the rest on a "
                            "uniformly drawn free cell (default: the scenario's s_start_share, "
                            "0 for the built-ins: the paper's random starts; e.g. 0.1 on maps "
                            "of 256 x 256 cells and more, where random starts rarely come near S)")


def s_starts_arg(args: argparse.Namespace) -> float | None:
    """``--s-starts`` checked now (exit 2 on a bad value); None: the scenario's own."""
    share = getattr(args, "s_starts", None)
    if share is None:
        return None
    if not (0.0 <= share < 1.0):
        raise CliError("command line", "--s-starts", f"must be in [0, 1), got {share:g}",
                       "pass e.g. --s-starts 0.1 (one episode in ten starts at S)")
    return share


def starts_note(sc) -> str:
    """What the output says about episode starts (empty for the paper's random starts)."""
    share = sc.s_start_share
    return f"; {share:.0%} of episodes start at S" if share > 0 else ""


def rewards_arg(args: argparse.Namespace) -> str | None:
    """The reward scheme a training command uses: ``--rewards``, else goal-only; None for
    ``--rewards scenario`` (the scenario file's own scheme)."""
    if args.rewards is None:
        return DEFAULT_REWARDS
    if args.rewards == "scenario":
        return None
    if "=" not in args.rewards and args.rewards.strip() not in REWARD_SCHEMES:
        raise CliError("command line", "--rewards", f"unknown reward scheme {args.rewards!r}",
                       f"use one of: {', '.join(REWARD_SCHEMES)}, scenario (the scenario "
                       "file's own), or goal=..,bump=..,step=..")
    return args.rewards


def rewards_note(args: argparse.Namespace) -> str:
    """What the output says about a default reward scheme (empty when one was given)."""
    if args.rewards is not None:
        return ""
    return ", this tool's default (the paper's own scheme is --rewards paper)"


def add_fidelity_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--fidelity", default=None, metavar="NAME|KEY=VALUE,...",
                   help="physics fidelity, a rung of the ladder: exact (default), noisy "
                        "(wheel_noise=0.05, carried_pose=true), slippery (wheel_noise=0.15), "
                        "uncalibrated (noisy + a per-run wheel-diameter and wheelbase bias, 1 "
                        "%% sigma), open-loop (uncalibrated, primitives without feedback), "
                        "localised (uncalibrated, pose from odometry and a fix every 5 "
                        "primitives), latency (noisy, wheels lagging 0.2 s, commands a "
                        "period late), slip (noisy, a wheel slip every 10 s); or a preset "
                        "then knobs, e.g. noisy,wheel_noise=0.1 "
                        "(every knob, with units: docs/fidelity.md). Above exact, "
                        "greedy tests drive 10 rollouts and the final policy 50 (physics "
                        "runs only)")


def add_world_args(p: argparse.ArgumentParser, worlds: str) -> None:
    """``--world`` (``worlds``: its help) and ``--fidelity``: the commands that train or drive."""
    p.add_argument("--world", default="grid", help=worlds)
    add_fidelity_arg(p)


def add_training_args(p: argparse.ArgumentParser, worlds: str, sweep: bool = False) -> None:
    """``--episodes``, :func:`add_world_args` and ``--set``: train, and compare (``sweep``:
    several runs and methods)."""
    p.add_argument("--episodes", type=int, default=3000,
                   help="training episodes per run" if sweep else "training episodes")
    add_world_args(p, worlds)
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help="override a config field for every method that has it" if sweep
                   else "override a config field, e.g. --set alpha=0.2 (repeatable)")


def fidelity_arg(args: argparse.Namespace) -> Fidelity | None:
    """``--fidelity``, parsed and checked now (one line, exit 2 on a bad value): the one
    parse of the flag, its :class:`Fidelity` carried from here to the kernel; None for
    ``exact`` (the scenario's own ``[physics]`` table then applies)."""

    text = getattr(args, "fidelity", None)
    if text is None:
        return None
    worlds = str(getattr(args, "world", None) or "")
    if worlds and "physics" not in worlds.split(","):
        raise CliError("command line", "--fidelity", f"{text!r} applies to the physics world "
                       f"only, and this run is in {worlds!r}",
                       "add --world physics (or grid,physics), or drop --fidelity")
    # an explicit --fidelity wins over the scenario's [physics] table, exact included
    return parse_fidelity(text)


def add_record_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--record", nargs="?", const=RECORD_DEFAULT, default=None,
                   metavar="PATH.rrd",
                   help="write a Rerun recording (default: recordings/<scenario>-<method>-"
                        "<world>-s<seed>.rrd; compare: recordings/<scenario>-compare.rrd)")
    p.add_argument("--record-every", type=int, default=None, metavar="N",
                   help="record every N-th episode in full (always the first, the last and "
                        "the greedy tests; default 10, in a comparison 100)")
    p.add_argument("--record-values-every", type=int, default=300, metavar="K",
                   help="log the V_NN / max Q heat maps and the policy every K episodes "
                        "(default 300)")


def scenario_from_args(args: argparse.Namespace):  # -> Scenario
    return load(*scenario_key(args), getattr(args, "rewards", None))[0]


def scen_problem(args: argparse.Namespace):  # -> (map path, ScenProblem)
    """The ``.scen`` problem chosen by ``--index`` or ``--bucket``; errors name the fix."""
    path = Path(args.scen)
    if not path.is_file():
        raise CliError(str(path), "--scen", "is not a file", "pass a Moving AI .scen file")
    problems = load_scen(path)
    if not problems:
        raise CliError(str(path), "--scen", "holds no problems", "pass a non-empty .scen file")
    if (args.index is None) == (args.bucket is None):
        raise CliError("command line", "--scen", "needs exactly one of --index N or --bucket B",
                       f"add e.g. --index 0 (0..{len(problems) - 1})")
    if args.index is not None:
        if not 0 <= args.index < len(problems):
            raise CliError(str(path), "--index", f"{args.index} is out of range",
                           f"use 0..{len(problems) - 1}")
        problem = problems[args.index]
    else:
        in_bucket = [q for q in problems if q.bucket == args.bucket]
        if not in_bucket:
            buckets = sorted({q.bucket for q in problems})
            raise CliError(str(path), "--bucket", f"no problem in bucket {args.bucket}",
                           f"use one of {buckets[0]}..{buckets[-1]}")
        problem = max(in_bucket, key=lambda q: q.optimal_length)
    map_path = path.parent / problem.map_name
    if Path(problem.map_name).is_absolute() or ".." in Path(problem.map_name).parts or \
            map_path.suffix != ".map" or not map_path.is_file():
        raise CliError(str(path), "map column", f"names {problem.map_name!r}, not a .map file "
                       f"beside the .scen", "put the .map next to the .scen and name it there")

    grid = load_map(map_path)
    if (grid.width, grid.height) != (problem.width, problem.height):
        raise CliError(str(path), "width/height columns", f"say {problem.width}x"
                       f"{problem.height} but {map_path.name} is {grid.width}x{grid.height}",
                       "use the .scen file that belongs to this map")
    return map_path, problem


def parse_overrides(items: list[str] | None) -> tuple[tuple[str, float], ...]:
    out = []
    for item in items or []:
        key, sep, value = item.partition("=")
        try:
            if not sep:
                raise ValueError
            out.append((key.strip(), float(value)))
        except ValueError:
            raise ExperimentError("command line", f"--set {item}", "expected FIELD=NUMBER",
                                  "write e.g. --set alpha=0.2") from None
    return tuple(out)


def parse_list(text: str, flag: str, allowed: tuple[str, ...] | None = None) -> list[str]:
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise ExperimentError("command line", flag, "is empty", f"give e.g. {flag} a,b")
    if allowed is not None:
        bad = [t for t in items if t not in allowed]
        if bad:
            raise ExperimentError("command line", flag, f"unknown value {bad[0]!r}",
                                  f"use one of: {', '.join(allowed)}")
    return items


def check_world(world: str) -> str:
    if world not in WORLDS:
        raise ExperimentError("command line", "--world", f"unknown world {world!r}",
                              f"use one of: {', '.join(WORLDS)}")
    return world




def positive(value: int, flag: str, limit: int | None = None) -> int:
    if value < 1:
        raise ExperimentError("command line", flag, f"must be >= 1, got {value}",
                              f"pass e.g. {flag} 10")
    if limit is not None and value > limit:
        raise ExperimentError("command line", flag, f"is {value}, more than the limit {limit:,}",
                              f"pass at most {flag} {limit}")
    return value


def seed_value(value: int, flag: str, count: int = 1) -> int:
    """A seed (or the first of ``count``): numpy seeds are non-negative integers."""
    if value < 0:
        raise ExperimentError("command line", flag, f"must be >= 0, got {value}",
                              f"pass e.g. {flag} 0")
    if value + count - 1 > MAX_SEED:
        raise ExperimentError("command line", flag, f"is {value}, beyond the largest seed "
                              f"{MAX_SEED}", f"pass e.g. {flag} 0")
    return value


def unique(items: list[str], flag: str) -> list[str]:
    """The items, refusing repeats (two identical runs would count as two seeds)."""
    seen = [t for i, t in enumerate(items) if t in items[:i]]
    if seen:
        raise ExperimentError("command line", flag, f"names {seen[0]!r} twice",
                              "list each value once")
    return items


def scenario_key(args: argparse.Namespace) -> tuple[str, tuple | None, tuple | None]:
    """(scenario spec, start, goal) from the positional scenario, --start/--goal or --scen."""
    if getattr(args, "scen", None):
        if args.scenario or args.start or args.goal:
            raise CliError("command line", "--scen", "sets the map, start and goal itself",
                           "drop the scenario argument and --start/--goal, or drop --scen")
        map_path, problem = scen_problem(args)
        print(f"{args.scen}: problem {map_path.name} {problem.start_xy} -> {problem.goal_xy} "
              f"(Moving AI frame; reference length {problem.optimal_length:g}, octile)")
        return str(map_path), problem.start_xy, problem.goal_xy
    for flag in ("index", "bucket"):
        if getattr(args, flag, None) is not None:
            raise CliError("command line", f"--{flag}", "only applies with --scen",
                           f"add --scen FILE.scen, or drop --{flag}")
    if not args.scenario:
        raise CliError("command line", "scenario", "is missing",
                       "name a built-in (rnhql scenarios), a .toml, a .map, or give --scen")
    start = parse_cell(args.start, "--start") if args.start else None
    goal = parse_cell(args.goal, "--goal") if args.goal else None
    return args.scenario, start, goal


@dataclass(frozen=True)
class Problem:
    """What a training command runs on, from its flags (each checked before any work):
    the scenario key and options as :class:`scenarios.runs.spec.RunSpec` holds them, and
    the loaded scenario and grid model."""

    scenario: str  # built-in name, .toml or .map path
    start: Cell | None  # --start (Moving AI frame) or the --scen problem's
    goal: Cell | None
    rewards: str | None  # rewards_arg
    s_starts: float | None  # s_starts_arg
    fidelity: Fidelity | None  # fidelity_arg
    sc: Scenario
    model: TabularModel

    @property
    def key(self) -> tuple[str, Cell | None, Cell | None, str | None, float | None]:
        """What :func:`scenarios.runs.spec.load` takes (a spec's ``problem``)."""
        return self.scenario, self.start, self.goal, self.rewards, self.s_starts

    def spec_fields(self) -> dict[str, object]:
        """The keyword arguments of a :class:`~scenarios.runs.spec.RunSpec` (and of
        ``make_specs``) that come from the problem."""
        return dict(start=self.start, goal=self.goal, rewards=self.rewards,
                    fidelity=self.fidelity, s_starts=self.s_starts)


def problem_arg(args: argparse.Namespace) -> Problem:
    """The scenario, ``--rewards``, ``--s-starts`` and ``--fidelity`` of a training command,
    checked, with the scenario and its grid model loaded."""
    name, start, goal = scenario_key(args)
    rewards, s_starts = rewards_arg(args), s_starts_arg(args)
    sc, model = load(name, start, goal, rewards, s_starts)
    return Problem(name, start, goal, rewards, s_starts, fidelity_arg(args), sc, model)


def compile_notice(n_methods: int, physics: bool = False) -> None:
    """Say so when the numba kernels are not on disk yet: the first run compiles them
    (a minute or more on 2 cores) before any progress can show. ``physics``: the command
    drives the physics world, whose kernels compile on its first use (tens of seconds)."""
    parts = []
    if n_methods and not kernels_cached():
        parts.append(f"the numba kernels of {n_methods} method{'' if n_methods == 1 else 's'}")
    if physics and not physics_cached():
        parts.append("the physics world's kernels")
    if parts:
        print(f"compiling {' and '.join(parts)} (first run only; cached on disk afterwards)",
              file=sys.stderr, flush=True)


# ---------------------------------------------------------------- one table: flags <-> the
# library's arguments. The library (scenarios.api) checks every argument; a subcommand passes
# its flags through as arguments and, when the library refuses one, says so in flag words
# (``scenarios.api.train: episodes`` -> ``command line: --episodes``, the same problem and
# fix), so a check, limit or default lives once, in the library.

# library argument -> the flag that sets it (the same for every subcommand that has it)
FLAG_OF = {
    "scenario": "scenario", "method": "--method", "methods": "--methods",
    "world": "--world", "worlds": "--world", "fidelity": "--fidelity",
    "episodes": "--episodes", "seed": "--seed", "seeds": "--seeds", "seed_base": "--seed-base",
    "rewards": "--rewards", "settings": "--set", "s_starts": "--s-starts",
    "start": "--start", "goal": "--goal", "jobs": "--jobs", "backend": "--backend",
    "address": "--address", "out": "--out", "resume": "--resume", "save": "--save",
    "record": "--record", "record_every": "--record-every",
    "record_values_every": "--record-values-every", "record_seeds": "--record-seeds",
    "init": "--init", "pretrain": "--pretrain", "drives": "--drives",
    "samples": "--samples", "rollouts": "--rollouts", "repeats": "--repeats",
    "pairs": "--pairs", "policies": "--policy", "agents": "--agent", "agent": "--agent",
}


def flag_words(err: InputError, renamed: dict[str, str] | None = None) -> InputError:
    """``err`` as the command says it: a library argument named by its flag, ``arg=value``
    in the fix written ``--flag value``; errors from elsewhere (a file, a field) unchanged."""
    if not err.source.startswith("scenarios.api."):
        return err
    if ": " in err.source:  # a part of an argument ("scenarios.api.optimum: fidelity")
        flag = (renamed or {}).get(err.source.split(": ", 1)[1]) or \
            FLAG_OF.get(err.source.split(": ", 1)[1])
        if flag is not None:
            return type(err)("command line", f"{flag}: {err.field}", err.problem, err.fix)
    name = err.field.split("[", 1)[0]
    flag = (renamed or {}).get(name) or FLAG_OF.get(name)
    if flag is None:
        return err
    field = flag + err.field[len(name):]

    def say(text: str) -> str:
        for arg, fl in FLAG_OF.items():
            # arg=('grid', 300) -> --pretrain grid:300, arg=(3, 5) -> --start 3,5; arg='x' ->
            # --flag x; arg=3 -> --flag 3; "drop arg=..." -> "drop --flag"; never in a path
            join = ":" if arg == "pretrain" else ","
            text = re.sub(rf"(?<![\w/.-]){arg}=\(([^)]*)\)", lambda m, fl=fl, j=join: f"{fl} "
                          + j.join(v.strip(" '\"") for v in m[1].split(",")), text)
            text = re.sub(rf"(?<![\w/.-]){arg}=\.\.\.", fl, text)
            text = re.sub(rf"(?<![\w/.-]){arg}='([^']*)'", rf"{fl} \1", text)
            text = re.sub(rf"(?<![\w/.-]){arg}=([^\s,;)'/]+)", rf"{fl} \1", text)
        return text

    out = type(err)("command line", field, err.problem, say(err.fix))
    return out


@contextlib.contextmanager
def in_flag_words(**renamed: str) -> Iterator[None]:
    """Library errors raised in the block reach the user in flag words (exit 2);
    ``renamed``: this subcommand's flag for an argument (compare: ``method="--methods"``)."""
    try:
        yield
    except InputError as err:
        raise flag_words(err, renamed) from None
