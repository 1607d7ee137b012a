"""Facts about scenarios for ``rnhql scenarios``: size, free cells, optimal route."""

from __future__ import annotations

import argparse
from dataclasses import dataclass

from scenarios.artifacts import cog_out
from scenarios.cli.args import scenario_from_args
from sim.grid import build_model
from sim.scenario import Scenario
from sim.scenario_io import builtin_dir, builtin_names, resolve_scenario


@dataclass(frozen=True)
class ScenarioFacts:
    name: str
    size_cells: tuple[int, int]
    size_m: tuple[float, float]
    obstacles: int
    blocked_map_cells: int
    free_cells: int
    start: tuple[int, int]
    goal: tuple[int, int]
    optimal_route_length: int  # BFS moves S -> G, 4-connected, inflated robot
    manhattan: int
    description: str

    def row(self) -> list[str]:
        return [self.name, f"{self.size_cells[0]}x{self.size_cells[1]}",
                f"{self.size_m[0]:g}x{self.size_m[1]:g} m",
                str(self.obstacles), str(self.blocked_map_cells), str(self.free_cells),
                f"{self.start}", f"{self.goal}", str(self.optimal_route_length),
                str(self.manhattan)]


HEADER = ["scenario", "cells", "size", "circles", "blocked map cells", "free", "start", "goal",
          "optimal", "manhattan"]


def facts(sc: Scenario) -> ScenarioFacts:
    m = build_model(sc)
    return ScenarioFacts(
        name=sc.name, size_cells=(sc.nx, sc.ny), size_m=(sc.width_m, sc.height_m),
        obstacles=len(sc.obstacles), blocked_map_cells=len(sc.blocked_cells),
        free_cells=int((~m.blocked).sum()), start=sc.start, goal=sc.goal,
        optimal_route_length=m.optimal_route_length,
        manhattan=abs(sc.start[0] - sc.goal[0]) + abs(sc.start[1] - sc.goal[1]),
        description=sc.description)


def builtin_facts() -> list[ScenarioFacts]:
    return [facts(resolve_scenario(name)) for name in builtin_names()]


def format_table(rows: list[list[str]], header: list[str]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(lines)


def example_toml() -> str:
    """A complete scenario file, every field commented (``rnhql scenarios --example``)."""
    return (builtin_dir() / "example.toml.txt").read_text(encoding="utf-8")


def cmd_scenarios(args: argparse.Namespace) -> int:
    if getattr(args, "example", False):
        print(example_toml(), end="")
        return 0
    if args.check or args.scen:
        args.scenario = args.check
        f = facts(scenario_from_args(args))
        print(f"{args.check or args.scen}: OK")
        print(format_table([f.row()], HEADER))
        return 0
    rows = builtin_facts()
    print(format_table([f.row() for f in rows], HEADER))
    print("\noptimal = BFS moves from start to goal for the inflated robot (4-connected).")
    return 0


def scenario_table() -> str:
    """The built-in scenarios, listed from the code (not a measurement: no artifact)."""
    lines = ["| scenario | cells | circles | blocked map cells | free cells | S | G | "
             "BFS route (moves) | what it is |", "|---|---|---|---|---|---|---|---|---|"]
    for name in builtin_names():
        sc = resolve_scenario(name)
        m = build_model(sc)
        desc = " ".join(sc.description.split()) or "—"
        lines.append(f"| `{name}` | {sc.nx}×{sc.ny} | {len(sc.obstacles)} | "
                     f"{len(sc.blocked_cells)} | {int((~m.blocked).sum())} | {sc.start} | "
                     f"{sc.goal} | {m.optimal_route_length} | {desc} |")
    return "\n".join(lines) + "\n"


def show_scenarios() -> None:
    """For a Cog block (docs/scenarios.md): the scenario table."""
    cog_out(scenario_table())
