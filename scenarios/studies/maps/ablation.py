"""The RNH-QL+ ablation: rnh-ql, then each ingredient added in turn up to rnh-ql+,
with dyna-q and q-lambda for reference, on every map of the suite (goal-only rewards).

``python -m scenarios.studies.maps.ablation --out results/ablation --seeds 10 --episodes 3000
--jobs 2`` builds the suite (:mod:`scenarios.studies.maps.suite`) in ``OUT/suite`` and writes
``OUT/ablation.md`` (the table), ``OUT/ablation.json`` (per-run figures and the summary) and
``OUT/ablation.png``. It is a sweep of :func:`scenarios.sweep.run.run_sweep` with
files of its own: while it runs, ``OUT/runs.partial.jsonl`` holds a line per finished run;
after Ctrl-C the same command with ``--resume`` runs only the rest (a finished ablation is
not read back: its runs carry no keys).

Cells: seeds whose final greedy route from S is optimal, then the median [q25, q75] over
seeds of *episodes to stable optimal*: episodes trained at the first greedy test (every 10
episodes) from which every later test through the last is optimal (``never`` sorts last).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.metrics import episodes_to_stable_optimal
from scenarios.artifacts import ROOT, load_artifact, write_artifact
from scenarios.figures.save import save_figure
from scenarios.runs.spec import RunSpec
from scenarios.runs.statistics import quantile
from scenarios.script_args import arg, artifact_arg, jobs_arg, parse, parser_of
from scenarios.studies.maps.suite import build_suite
from scenarios.sweep.run import SweepFiles, ctrl_c_held, run_sweep
from sim.files import atomic_write_text

# label, method, overrides: each row adds one ingredient to the row above it, down to
# rnh-ql+; the rows after it take one ingredient away again, or are references. A row that
# turns a switch rnh-ql+ no longer has (a network potential, the RBF lattice, re-based rows)
# runs on the ablation's method, which is rnh-ql+ run for run at its defaults.
ABL = "rnh-ql+ablation"
_V1 = (("v_target", 1), ("shaping_scale", 0.25), ("rebase", 1), ("lookahead", 0))
_OFF = (("v_target", 0), ("warmup_episodes", 300), ("shaping_scale", 1.0), ("rebase", 0),
        ("n_planning", 0), ("lookahead", 0))
# The rows before +E have no known-route test: it is one of +E's ingredients (without it a
# row's greedy test reads its own values; with it, any row that keeps a move model is graded
# on the shortest route it has walked, whatever its potential).
_NO_KNOWN = (("known_route", 0),)
VARIANTS: list[tuple[str, str, tuple[tuple[str, float], ...]]] = [
    ("rnh-ql", "rnh-ql", ()),
    ("+A lattice every 4 cells, sparse (cut-off 2 widths)", ABL, _OFF + _NO_KNOWN),
    ("+B V_NN toward max Q + Phi, no warm-up", ABL, _V1[:2] + _OFF[2:] + _NO_KNOWN),
    ("+C re-based rows, Phi = 0.25 V_NN", ABL, _V1 + _OFF[4:5] + _NO_KNOWN),
    ("+D 10 shaped planning updates", ABL, _V1 + _NO_KNOWN),
    ("+E Phi = the optimistic model's value, look-ahead on untried moves, no re-basing, "
     "the known-route test (= rnh-ql+)", "rnh-ql+", ()),
    ("rnh-ql+, V_NN (a centre per cell) learns that value", ABL,
     (("v_target", 3), ("spacing", 1), ("sigma", 0.5), ("n_fit", 10), ("beta", 0.5))),
    ("rnh-ql+, V_NN learns the table's value over it (residual)", ABL, (("v_target", 5),)),
    ("rnh-ql+ without look-ahead", "rnh-ql+", (("lookahead", 0),)),
    ("rnh-ql+ without planning", "rnh-ql+", (("n_planning", 0),)),
    ("rnh-ql+ without the known-route test", "rnh-ql+", (("known_route", 0),)),
    ("dyna-q", "dyna-q", ()),
    ("dyna-q, 10 planning updates (rnh-ql+'s budget)", "dyna-q", (("n_planning", 10),)),
    ("q-lambda", "q-lambda", ()),
    ("haql (heuristic from exploration)", "haql", ()),
    ("rnh-ql+ with prioritized sweeping (an option, off by default)", "rnh-ql+",
     (("sweeping", 1),)),
]


def stable_optimal(test_episodes: list[int], lengths: list[int], optimal: int) -> int | None:
    """Episodes at the first test from which every later test is optimal (learning.metrics)."""
    return episodes_to_stable_optimal(np.asarray(test_episodes), np.asarray(lengths), optimal)


Row = tuple[str, str, tuple[tuple[str, float], ...]]  # label, method, overrides


def kept(rec: dict[str, Any]) -> dict[str, Any]:
    """What the ablation keeps of a run's record (its table's figures, not the per-episode
    arrays): ``stable_optimal`` is :func:`stable_optimal` of its greedy tests."""
    return dict(key=rec["key"], seed=rec["seed"], optimal=int(rec["optimal_route_length"]),
                final_route_optimal=bool(rec["final_route_optimal"]),
                final_route_length=rec["final_route_length"],
                first_optimal=rec["episodes_to_optimal"],
                stable_optimal=rec["episodes_to_stable_optimal"],
                env_steps=rec["env_steps"], wall_time_s=rec["wall_time_s"])


def ablation_specs(rows: Sequence[Row], maps: list[dict], seeds: int, episodes: int
                   ) -> list[tuple[str, str, RunSpec]]:
    """(label, map name, run) for every row x map x seed; two rows of the same method and
    overrides share their runs."""
    return [(lab, m["name"], RunSpec(m["file"], meth, s, episodes, overrides=tuple(ov)))
            for lab, meth, ov in rows for m in maps for s in range(seeds)]


def quartiles(xs: list[int | None]) -> tuple[float, float, float]:
    """(median, q25, q75) by the one quantile definition (scenarios.runs.statistics.quantile:
    type 7, None = never = +inf sorts last)."""
    if not xs:
        return math.inf, math.inf, math.inf
    return tuple(quantile(list(xs), q) for q in (0.5, 0.25, 0.75))


def _fmt(x: float) -> str:
    return "never" if math.isinf(x) else f"{x:.0f}"


def summarise(runs: list[dict], maps: list[dict], labels: list[str]) -> dict:
    out: dict[str, dict[str, Any]] = {}
    for lab in labels:
        out[lab] = {}
        for m in maps:
            rs = [r for r in runs if r["label"] == lab and r["map"] == m["name"]]
            if not rs:
                continue
            med, q25, q75 = quartiles([r["stable_optimal"] for r in rs])
            out[lab][m["name"]] = dict(optimal_seeds=sum(r["final_route_optimal"] for r in rs),
                                       seeds=len(rs), median=med, q25=q25, q75=q75)
    return out


def table(summary: dict, maps: list[dict], labels: list[str]) -> str:
    head = "| variant | " + " | ".join(
        f"{m['name']}{' (held out)' if m['held_out'] else ''}" for m in maps) + " |"
    lines = [head, "|" + "---|" * (len(maps) + 1)]
    for lab in labels:
        cells = []
        for m in maps:
            c = summary.get(lab, {}).get(m["name"])
            cells.append("" if c is None else
                         f"{c['optimal_seeds']}/{c['seeds']} · {_fmt(c['median'])} "
                         f"[{_fmt(c['q25'])}, {_fmt(c['q75'])}]")
        lines.append(f"| {lab} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def target_seeds(seeds: int) -> int:
    """Optimal seeds a map needs to count as solved: 9 of 10, and 90 % of any other count
    (3 of 3, not 9 of 3)."""
    return math.ceil(0.9 * seeds - 1e-9)


def compact_table(summary: dict, maps: list[dict], labels: list[str], min_seeds: int) -> str:
    """The README's form: optimal seeds · median episodes (— never), and how many maps reach
    ``min_seeds`` optimal seeds."""
    head = "| variant | " + " | ".join(
        m["name"] + ("*" if m["held_out"] else "") for m in maps) + f" | maps ≥ {min_seeds} |"
    lines = [head, "|" + "---|" * (len(maps) + 2)]
    for lab in labels:
        cells, good, have = [], 0, 0
        for m in maps:
            c = summary.get(lab, {}).get(m["name"])
            if c is None:
                cells.append("")
                continue
            have += 1
            good += c["optimal_seeds"] >= min_seeds
            med = "—" if math.isinf(c["median"]) else f"{c['median']:.0f}"
            cells.append(f"{c['optimal_seeds']} · {med}")
        lines.append(f"| {lab} | " + " | ".join(cells) + f" | {good}/{have} |")
    return "\n".join(lines)


def verdict(summary: dict, maps: list[dict], ours: str, ref: str, min_seeds: int,
            open_maps: tuple[str, ...] = ("paper-40", "paper-50"),
            max_median: float = 650.0) -> list[str]:
    """The ablation's targets, judged from the summary: ``ours`` reaches ``min_seeds`` optimal
    seeds on every map, a median of at most ``max_median`` episodes on ``open_maps``, at
    least ``ref``'s optimal seeds everywhere and fewer median episodes on most maps."""
    a, b = summary.get(ours, {}), summary.get(ref, {})
    names = [m["name"] for m in maps if m["name"] in a]
    if not names:
        return []
    short = [n for n in names if a[n]["optimal_seeds"] < min_seeds]
    slow = [n for n in open_maps if n in a and a[n]["median"] > max_median]
    line = (f"- `{ours}`: ≥ {min_seeds} optimal seeds on {len(names) - len(short)}/{len(names)} "
            "maps" + (f" (short on {', '.join(short)})" if short else ""))
    shown = [n for n in open_maps if n in a]
    if shown:
        line += ("; median episodes to stable optimal on "
                 + ", ".join(f"{n} {_fmt(a[n]['median'])}" for n in shown)
                 + (f" (above {max_median:.0f} on {', '.join(slow)})" if slow else
                    f" (all ≤ {max_median:.0f})"))
    out = [line]
    both = [n for n in names if n in b]
    if both:
        fewer_seeds = [n for n in both if a[n]["optimal_seeds"] < b[n]["optimal_seeds"]]
        faster = [n for n in both if a[n]["median"] < b[n]["median"]]
        slower = [n for n in both if a[n]["median"] > b[n]["median"]]
        out.append(f"- against `{ref}`: at least as many optimal seeds on "
                   f"{len(both) - len(fewer_seeds)}/{len(both)} maps"
                   + (f" (fewer on {', '.join(fewer_seeds)})" if fewer_seeds else "")
                   + f"; fewer median episodes on {len(faster)}/{len(both)}"
                   + (f", more on {', '.join(slower)}" if slower else ""))
    return out


def figure(summary: dict, maps: list[dict], labels: list[str], path: Path, title: str) -> None:
    """Variants x maps: colour = seeds whose final route is optimal, text = that count and the
    median episodes to a stable optimal route."""
    # lazy: matplotlib costs 270 ms at import, in each spawned sweep worker too
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = np.full((len(labels), len(maps)), np.nan)
    fig, ax = plt.subplots(figsize=(2.0 + 0.75 * len(maps), 1.2 + 0.55 * len(labels)), dpi=110)
    for i, lab in enumerate(labels):
        for j, m in enumerate(maps):
            c = summary.get(lab, {}).get(m["name"])
            if c is None:
                continue
            grid[i, j] = c["optimal_seeds"] / c["seeds"]
            med = "—" if math.isinf(c["median"]) else f"{c['median']:.0f}"
            ax.text(j, i, f"{c['optimal_seeds']}\n{med}", ha="center", va="center", fontsize=6)
    ax.imshow(grid, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
    ax.set_xticks(range(len(maps)), [m["name"] + ("*" if m["held_out"] else "") for m in maps],
                  rotation=45, ha="right", fontsize=7)
    ax.set_yticks(range(len(labels)), [textwrap.fill(lab, 46) for lab in labels], fontsize=7)
    ax.set_title(title, fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def ablation_files(rows: Sequence[Row], maps: list[dict], labelled: list[tuple[str, str, RunSpec]],
                   rewards: str, seeds: int, episodes: int) -> SweepFiles:
    """The ablation's files: ``ablation.md``, ``ablation.json``, ``ablation.png``."""
    labels = [r[0] for r in rows]

    def write(_specs: Sequence[RunSpec], records: list[dict[str, Any]], out: Path
              ) -> dict[str, Any]:
        by_key = {r["key"]: r for r in records}
        runs = []
        for lab, map_name, spec in labelled:
            r = by_key[spec.key]
            runs.append(dict(map=map_name, label=lab, seed=r["seed"], optimal=r["optimal"],
                             final_route_optimal=r["final_route_optimal"],
                             final_route_length=r["final_route_length"],
                             first_optimal=r["first_optimal"],
                             stable_optimal=r["stable_optimal"], env_steps=r["env_steps"],
                             wall_time_s=r["wall_time_s"], episodes=episodes))
        summary = summarise(runs, maps, labels)
        md = (f"Rewards `{rewards}`, {seeds} seeds x {episodes} episodes. Cell: seeds whose "
              "final greedy route is optimal · median [q25, q75] episodes to stable optimal "
              "(`*`/held out: maps generated from seeds nobody tuned on).\n\n"
              + table(summary, maps, labels) + "\n")
        ours = next((lab for lab in labels if lab.endswith("(= rnh-ql+)")), None)
        lines: list[str] = []
        for ref in [lab for lab in labels if lab.startswith("dyna-q")] if ours else []:
            got = verdict(summary, maps, ours, ref, target_seeds(seeds))
            lines += got if not lines else got[1:]
        if lines:
            md += ("\nTargets of the rnh-ql+ study, computed from the table:\n\n"
                   + "\n".join(lines) + "\n")
        md += ("\nCompact (optimal seeds · median episodes to stable optimal, — never):\n\n"
               + compact_table(summary, maps, labels, target_seeds(seeds)) + "\n")
        payload = dict(maps=maps, variants=[dict(label=lab, method=m, overrides=dict(ov))
                                            for lab, m, ov in rows],
                       summary=summary, runs=runs)
        atomic_write_text(out / "ablation.md", md)
        atomic_write_text(out / "ablation.json", json.dumps(payload, indent=1, default=str))
        with ctrl_c_held():
            figure(summary, maps, labels, out / "ablation.png",
                   f"rnh-ql+ ablation, rewards {rewards}, {seeds} seeds x {episodes} episodes: "
                   "optimal seeds (colour, top) and median episodes to stable optimal (bottom)")
        print(md)
        return payload

    return SweepFiles(write, keep=kept, finished=lambda _out: {})


@dataclass(frozen=True)
class Args:
    out: str = arg("results/ablation", "output folder")
    seeds: int = arg(10, "seeds per cell (0 .. N-1)")
    episodes: int = arg(3000, "episodes per run")
    jobs: int | None = jobs_arg()
    resume: bool = arg(False, "after Ctrl-C: run only the runs not finished yet")
    maps: str = arg("", "comma-separated suite names, or held-out (default: all)")
    variants: str = arg("", "comma-separated labels or row numbers (0-based) of the table "
                        "(default: all)")
    extra: list[str] | None = arg(  # noqa: RUF009 (arg is a dataclasses.field)
        None, "an extra row METHOD[:FIELD=VALUE,...] (e.g. "
        "rnh-ql+:n_planning=10, rnh-ql+ablation:v_target=1); repeat for more",
        action="append")
    rewards: str = arg("goal-only", "reward scheme of the suite")
    held_out_seeds: str = arg("101,102", "generator seeds of the held-out maze and rooms maps "
                              "(e.g. 101,...,110)")
    artifact: str | None = artifact_arg("ablation")


def main(argv: list[str] | None = None) -> int:
    a = parse(Args, __doc__, argv)
    out = Path(a.out)
    try:
        held = tuple(int(x) for x in a.held_out_seeds.split(",") if x)
    except ValueError:
        parser_of(Args, __doc__).error(f"--held-out-seeds: {a.held_out_seeds!r} is not a "
                                       "comma-separated list of integers")
    maps = build_suite(out / "suite", a.rewards, held_out_seeds=held)
    if a.maps == "held-out":
        maps = [m for m in maps if m["held_out"]]
    elif a.maps:
        want = a.maps.split(",")
        maps = [m for m in maps if m["name"] in want]
    rows = list(VARIANTS)
    if a.variants:
        keys = a.variants.split(",")
        rows = [v for i, v in enumerate(VARIANTS) if v[0] in keys or str(i) in keys]
    for ex in a.extra or ():
        method, _, sets = ex.partition(":")
        ov = tuple((k, float(v)) for k, v in (kv.split("=") for kv in sets.split(",") if kv))
        rows.append((f"{method}|{sets}" if sets else method, method, ov))
    # looked up per call: tests/test_experiments_ablation.py stands in for run_local
    from scenarios.sweep.backends import Progress, run_local

    labelled = ablation_specs(rows, maps, a.seeds, a.episodes)
    specs = list({spec.key: spec for _, _, spec in labelled}.values())
    payload = run_sweep(specs, out, run_local, resume=a.resume,
                        files=ablation_files(rows, maps, labelled, a.rewards, a.seeds,
                                             a.episodes),
                        jobs=a.jobs or os.cpu_count() or 1, progress=Progress(len(specs)))
    if a.artifact:
        write_ablation_artifact(a, [r[0] for r in rows], maps, payload["summary"],
                                sys.argv[1:] if argv is None else argv)
    return 0


def write_ablation_artifact(a: argparse.Namespace, labels: list[str], maps: list[dict],
                            summary: dict, argv: Sequence[str]) -> None:
    """``docs/results/ablation.NAME.json`` (what the README's table shows) and
    ``docs/ablation.png`` drawn from it."""
    data = {"rewards": a.rewards, "seeds": a.seeds, "episodes": a.episodes,
            "min_seeds": target_seeds(a.seeds),
            "maps": [{"name": m["name"], "held_out": m["held_out"]} for m in maps],
            "labels": labels, "summary": summary}
    write_artifact(f"ablation.{a.artifact}",
                   "python -m scenarios.studies.maps.ablation " + " ".join(argv),
                   ["grid"], data, study=__file__)
    with ctrl_c_held():
        figure_from_artifact(f"ablation.{a.artifact}", ROOT / "docs" / "ablation.png")


def figure_from_artifact(name: str, path: Path) -> None:
    """Draw the ablation's figure from artifact ``name`` (what ``rnhql report --figures``
    redraws ``docs/ablation.png`` with)."""
    d = load_artifact(name)["data"]
    summary = {lab: {m: {**c, "median": math.inf if c["median"] is None else c["median"]}
                     for m, c in row.items()} for lab, row in d["summary"].items()}
    figure(summary, d["maps"], d["labels"], path,
           f"rnh-ql+ ablation, rewards {d['rewards']}, {d['seeds']} seeds x {d['episodes']} "
           "episodes: optimal seeds (colour, top) and median episodes to stable optimal "
           "(bottom)")


if __name__ == "__main__":
    raise SystemExit(main())
