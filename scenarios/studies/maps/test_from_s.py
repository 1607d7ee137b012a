"""Where the greedy test from S goes wrong, one line per seed.

    python -m scenarios.studies.maps.test_from_s --problem rooms-256@uniform --method rnh-ql+ \\
        --seeds 5 --map-seed 7

Trains the method on a held-out problem (``MAP@PROTOCOL`` as in
:mod:`scenarios.studies.maps.heldout`, same budget), then walks its greedy test from S
and says: the route's length against the optimum; where it stopped (the first move
that did not bring it nearer G: a bump or a loop), how far from S that is, whether any
training episode acted in that cell, how many cells of the walk were ever acted in; the
share of the map's free cells acted in; and, for methods with an optimistic model
(``rnh-ql+``, ``haql``), how many moves there the model held equally short (a tie the
test broke by index) and whether the one taken was a wall.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from learning.drivers.train import greedy_test, train_tabular
from learning.methods.registry import family_of
from learning.streams import streams
from scenarios.artifacts import check_artifact_name, write_artifact
from scenarios.runs.spec import load, make_config
from scenarios.script_args import arg, parse, parser_of, study_command
from scenarios.studies.maps.heldout import method_of, share_of, write_problem


@dataclass(frozen=True)
class Args:
    problem: str = arg("rooms-256@uniform", "MAP@PROTOCOL (scenarios.studies.maps.heldout)")
    method: str = arg("rnh-ql+", "method, METHOD[:FIELD=V;FIELD=V]")
    seeds: int = arg(5, "seeds (0 .. N-1)")
    map_seed: int = arg(7, "generator seed of the map (7: the tuning set's)")
    braid: float = arg(0.02, "share of a generated maze's inner walls knocked out")
    maps: str = arg("results/test-from-s", "folder for the generated map and scenario")
    artifact: str | None = arg(None, "also write docs/results/test-from-s.NAME.json (a docs "
                                     "block, rendered by scenarios.artifacts)", metavar="NAME")


def acted_cells(state) -> np.ndarray | None:
    """bool[nS]: cells some move was tried from (None: the method keeps no move model)."""
    model = getattr(state, "model", None)
    succ = getattr(model, "successor", None)
    return None if succ is None else (np.asarray(succ) >= 0).any(axis=1)


def where_it_stops(route: list[int], distance: np.ndarray) -> int:
    """Index in ``route`` of the cell whose move did not bring the walk nearer G."""
    for i in range(1, len(route)):
        if distance[route[i]] >= distance[route[i - 1]]:
            return i - 1
    return len(route) - 1


def describe(seed: int, result, model, state) -> str:
    dist = np.asarray(model.distance_to_goal)
    length, route = greedy_test(state, model)
    test = length if length >= 0 else "no G"
    line = f"seed {seed}: test {test} (optimum {result.optimal_length})"
    acted = acted_cells(state)
    if acted is not None:
        free = dist >= 0
        line += f"; cells acted in {acted[free].mean():.0%}"
    if length >= 0:
        return line
    k = where_it_stops(route, dist)
    cell = route[k]
    line += f"; stops {k} moves from S, {dist[cell]} from G"
    if acted is not None:
        line += (f", a cell {'acted' if acted[cell] else 'never acted'} in; "
                 f"{int(acted[route[:k + 1]].sum())}/{k + 1} cells of the walk acted in")
    free_space = getattr(state, "free", None)
    if free_space is not None:
        nb, blocked, fd = free_space.neighbour, free_space.blocked, free_space.distance
        a = int(family_of(result.config).exploit(state, cell))
        best = [b for b in range(nb.shape[1]) if nb[cell, b] >= 0 and not blocked[cell, b]
                and fd[nb[cell, b]] == fd[cell] - 1]
        wall = model.next_state[cell, a] == cell
        line += (f"; the model's distance there {fd[cell]}, {len(best)} moves equally short, "
                 f"the test's move {'a wall' if wall else 'free'}")
    return line


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    if args.artifact:
        check_artifact_name(parser_of(Args, __doc__), args.artifact)

    name, _, protocol = args.problem.partition("@")
    share = share_of(protocol or "s10")
    toml, route, episodes = write_problem(name, share, args.map_seed, args.braid,
                                          Path(args.maps))
    _, model = load(str(toml), rewards="goal-only", s_starts=share)
    method, overrides = method_of(args.method)
    lines = [f"{args.problem}, map seed {args.map_seed}: optimum {route} moves, {episodes} "
             f"episodes, {args.method}"]
    print(lines[0])
    for seed in range(args.seeds):
        rs = streams(seed)
        result = train_tabular(make_config(method, overrides), model, episodes, rs.learner,
                               test_every=10, start_rng=rs.starts)
        lines.append(describe(seed, result, model, result.state))
        print(lines[-1], flush=True)
    if args.artifact:
        write_artifact(f"test-from-s.{args.artifact}", study_command(__spec__.name, Args, args),
                       ["grid"], {"lines": lines}, study=__file__)
    return 0


if __name__ == "__main__":
    sys.exit(main())
