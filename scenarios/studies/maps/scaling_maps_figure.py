"""The scaling study's log-log figure and growth exponents, from finished study folders.

    python -m scenarios.studies.maps.scaling_maps_figure --artifacts small seed7 512 \\
        --out docs/scaling-maps.png
    python -m scenarios.studies.maps.scaling_maps_figure results/scaling-maps --out x.png

Reads the committed artifacts ``docs/results/scaling-maps.NAME.json`` (their main rows,
not the ablation's), or the main sweep (``<kind>-<n>/sweep0/results.json``) of every
folder written by :mod:`scenarios.studies.maps.scaling_maps`, and draws, over the
number of free cells with a route to G on log-log axes, each method's median episodes to a
stable optimal route (bars: quartiles; a point only where at least half the seeds
have one) and its median wall time per run, one line per map kind. Beside the PNG it
writes a table (``.md``) of the points and of each line's exponent: the slope of a
least-squares line through the log-log points, over the sizes the line has.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from scenarios.artifacts import ArtifactError, cog_out, load_artifact, provenance
from scenarios.figures.mpl import pyplot
from scenarios.figures.save import save_figure
from scenarios.palette import method_colour_mpl
from scenarios.runs.spec import load
from scenarios.script_args import arg, parse, parser_of, positional
from scenarios.studies.paper.scaling import fit_exponent
from sim.files import atomic_write_text

MARKERS = {"city": "s", "maze": "^", "rooms": "D", "random": "o", "caves": "v"}
STYLES = {"rnh-ql+": "-", "haql": "--", "dyna-q": ":"}


@dataclass(frozen=True)
class Point:
    """One method on one map: the medians and quartiles of its seeds."""

    method: str
    kind: str
    size: int  # cells a side
    states: int  # free cells with a route to G (what the learner can explore)
    seeds: int
    optimal: int  # seeds whose final greedy route is optimal
    episodes: tuple[float | None, float | None, float | None]  # q25, median, q75 [episodes]
    wall: tuple[float, float, float]  # q25, median, q75 [s per run]


def read_points(folders: Sequence[Path]) -> list[Point]:
    """Every method's point on every map of the folders' main sweeps (a later folder's
    point for the same method, kind and size replaces an earlier one)."""
    found: dict[tuple[str, str, int], Point] = {}
    for folder in folders:
        paths = sorted(folder.glob("*-*/sweep0/results.json"))
        if not paths:
            raise FileNotFoundError(f"{folder}: no <kind>-<size>/sweep0/results.json in it; "
                                    "give a folder written by scenarios.studies."
                                    "scaling_maps")
        for path in paths:
            res = json.loads(path.read_text(encoding="utf-8"))
            kind, size = path.parent.parent.name.rsplit("-", 1)
            _, model = load(res["scenario"]["source"])
            for method, by_world in res["summary"].items():
                st = by_world["grid"]
                e, w = st["episodes_to_stable_optimal"], st["wall_time_s"]
                seeds = int(st["seeds"])
                found[(method, kind, int(size))] = Point(
                    method, kind, int(size), int((model.distance_to_goal >= 0).sum()), seeds,
                    round(st["optimal_route_fraction"] * seeds),
                    (e["q25"], e["median"], e["q75"]), (w["q25"], w["median"], w["q75"]))
    return sorted(found.values(), key=lambda p: (p.method, p.kind, p.size))


def points_from_artifacts(names: Sequence[str]) -> list[Point]:
    """The main rows (not the ablation's) of artifacts ``scaling-maps.NAME``; a later
    artifact's point for the same method, kind and size replaces an earlier one."""
    found: dict[tuple[str, str, int], Point] = {}
    for name in names:
        for p in load_artifact(f"scaling-maps.{name}")["data"]["points"]:
            if p["ablation"]:
                continue
            found[(p["method"], p["kind"], p["size"])] = Point(
                p["method"], p["kind"], p["size"], p["states"], p["seeds"], p["optimal"],
                tuple(p["episodes"]), tuple(p["wall"]))
    return sorted(found.values(), key=lambda p: (p.method, p.kind, p.size))


def figure_from_artifacts(*names: str, path: Path) -> Path:
    """The figure of artifacts ``scaling-maps.NAME`` (full names, as the report lists them)."""
    return draw(points_from_artifacts([n.removeprefix("scaling-maps.") for n in names]), path)


def lines(points: Sequence[Point]) -> dict[tuple[str, str], list[Point]]:
    out: dict[tuple[str, str], list[Point]] = {}
    for p in points:
        out.setdefault((p.method, p.kind), []).append(p)
    return out


def draw(points: Sequence[Point], path: Path) -> Path:
    plt = pyplot()

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), dpi=110)
    for (method, kind), pts in lines(points).items():
        colour = method_colour_mpl(method)
        style = dict(color=colour, ls=STYLES.get(method, "-."), marker=MARKERS.get(kind, "x"),
                     ms=5, capsize=2, lw=1.2)
        eps = [p for p in pts if p.episodes[1] is not None]
        if eps:
            med = np.array([p.episodes[1] for p in eps], float)
            lo = np.array([p.episodes[0] if p.episodes[0] is not None else p.episodes[1]
                           for p in eps], float)
            hi = np.array([p.episodes[2] if p.episodes[2] is not None else np.nan
                           for p in eps], float)
            hi = np.where(np.isnan(hi), med, hi)  # an upper quartile of "never": no bar up
            axes[0].errorbar([p.states for p in eps], med, yerr=[med - lo, hi - med], **style)
        wall = np.array([p.wall for p in pts], float)
        axes[1].errorbar([p.states for p in pts], wall[:, 1],
                         yerr=[wall[:, 1] - wall[:, 0], wall[:, 2] - wall[:, 1]], **style)
    for ax, label in zip(axes, ("episodes to a stable optimal route (median, quartiles)",
                                "wall time per run [s] (median, quartiles)"), strict=True):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("free cells with a route to G")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
    methods = list(dict.fromkeys(p.method for p in points))
    kinds = list(dict.fromkeys(p.kind for p in points))
    handles = [plt.Line2D([], [], color=method_colour_mpl(m), ls=STYLES.get(m, "-."), label=m)
               for m in methods]
    handles += [plt.Line2D([], [], color="0.3", ls="", marker=MARKERS.get(k, "x"), label=k)
                for k in kinds]
    for ax in axes:
        ax.legend(handles=handles, fontsize=7, loc="upper left", ncol=2)
    fig.suptitle("Route learning on generated maps of 64² to 512² cells (10 seeds each; "
                 "a point only where at least half the seeds reach a stable optimal route)",
                 fontsize=9)
    fig.tight_layout()
    out = save_figure(fig, path)
    plt.close(fig)
    return out


def table(points: Sequence[Point]) -> str:
    sizes = sorted({p.size for p in points})
    head = ("| method | kind | " + " | ".join(f"{n}²" for n in sizes)
            + " | exponent: episodes | exponent: wall time |")
    rows = [head, "|---|---|" + "---|" * (len(sizes) + 2)]

    def f(v: float | None) -> str:
        return "never" if v is None else f"{v:.0f}"

    for (method, kind), pts in lines(points).items():
        by = {p.size: p for p in pts}
        cells = []
        for n in sizes:
            p = by.get(n)
            cells.append("–" if p is None else
                         f"{p.states} cells: {p.optimal}/{p.seeds} · {f(p.episodes[1])} "
                         f"[{f(p.episodes[0])}, {f(p.episodes[2])}] · {p.wall[1]:.2f} s")
        ke = fit_exponent([p.states for p in pts], [p.episodes[1] for p in pts])
        kw = fit_exponent([p.states for p in pts], [p.wall[1] for p in pts])
        rows.append(f"| {method} | {kind} | " + " | ".join(cells)
                    + f" | {'–' if ke is None else f'{ke:.2f}'} | "
                    f"{'–' if kw is None else f'{kw:.2f}'} |")
    return "\n".join(rows) + "\n"


def points_text(points: Sequence[Point]) -> str:
    return ("Cells: free cells with a route to G: seeds optimal · median [q25, q75] episodes "
            "to a stable optimal route · median wall time per run. Exponents: least-squares "
            "slope over log free cells.\n\n" + table(points))


def render_points(names: Sequence[str]) -> None:
    """For a Cog block: every point of artifacts ``scaling-maps.NAME``, each artifact's
    provenance (and stale banner) under the table."""
    docs = [load_artifact(f"scaling-maps.{n}") for n in names]
    heads = [provenance(d).split("\n\n")[0] for d in docs if "\n\n" in provenance(d)]
    tails = [provenance(d).split("\n\n")[-1] for d in docs]
    cog_out("".join(h + "\n\n" for h in heads) + points_text(points_from_artifacts(names))
            + "\n" + "\n\n".join(tails) + "\n")


@dataclass(frozen=True)
class Args:
    folders: list[str] = positional(  # noqa: RUF009 (positional is a dataclasses.field)
        "output folders of scenarios.studies.maps.scaling_maps", nargs="*")
    artifacts: list[str] | None = arg(  # noqa: RUF009 (arg is a dataclasses.field)
        None, "read docs/results/scaling-maps.NAME.json instead of folders", nargs="+",
        metavar="NAME")
    out: str = arg("results/scaling-maps.png", "the figure (PNG); its table goes beside it "
                   "as .md")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    if bool(args.folders) == bool(args.artifacts):
        parser_of(Args, __doc__).error("give study folders or --artifacts NAME..., one of "
                                       "the two")

    try:
        points = (points_from_artifacts(args.artifacts) if args.artifacts
                  else read_points([Path(f) for f in args.folders]))
    except (FileNotFoundError, json.JSONDecodeError, KeyError, ArtifactError) as err:
        print(f"scaling_maps_figure: error: {err}", file=sys.stderr)
        return 2
    out = draw(points, Path(args.out))
    text = points_text(points)
    atomic_write_text(Path(args.out).with_suffix(".md"), text)
    print(text)
    print(f"wrote {out} and {Path(args.out).with_suffix('.md')}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
