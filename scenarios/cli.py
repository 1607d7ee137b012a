"""The ``rnhql`` command.

Every subcommand is a function ``cmd_<name>(args) -> int``. Input errors
(:class:`sim.errors.InputError` and its kin) are printed as one line and exit
with status 2; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from sim.errors import InputError


class CliError(InputError):
    """Bad command-line input that no lower layer can name better."""


def parse_cell(text: str, flag: str) -> tuple[int, int]:
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise CliError("command line", flag, f"expected X,Y integers, got {text!r}",
                       f"write e.g. {flag} 3,5") from None
    return x, y


def add_scenario_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help="built-in name (see `rnhql scenarios`), a .toml, or a .map")
    p.add_argument("--start", help="X,Y start for a .map (Moving AI frame: y counts down)")
    p.add_argument("--goal", help="X,Y goal for a .map (Moving AI frame: y counts down)")


def scenario_from_args(args: argparse.Namespace):  # -> Scenario
    from sim.scenario import resolve_scenario

    start = parse_cell(args.start, "--start") if args.start else None
    goal = parse_cell(args.goal, "--goal") if args.goal else None
    return resolve_scenario(args.scenario, start, goal)


def cmd_scenarios(args: argparse.Namespace) -> int:
    from scenarios.catalog import HEADER, builtin_facts, facts, format_table

    if args.check:
        args.scenario = args.check
        f = facts(scenario_from_args(args))
        print(f"{args.check}: OK")
        print(format_table([f.row()], HEADER))
        return 0
    rows = builtin_facts()
    print(format_table([f.row() for f in rows], HEADER))
    print("\noptimal = BFS moves from start to goal for the inflated robot (4-connected).")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rnhql",
        description="Route searching with RBF-network heuristic Q-learning (RNH-QL) and its "
                    "baselines, on a grid and in a Pymunk physics world.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("scenarios", help="list built-in scenarios or validate one")
    p.add_argument("--check", metavar="FILE", help="validate a .toml or .map and print its facts")
    p.add_argument("--start", help="X,Y start for a .map (Moving AI frame: y counts down)")
    p.add_argument("--goal", help="X,Y goal for a .map (Moving AI frame: y counts down)")
    p.set_defaults(func=cmd_scenarios)

    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as err:
        print(f"rnhql: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rnhql: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
