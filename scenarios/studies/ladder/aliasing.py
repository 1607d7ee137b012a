"""Aliasing: how many next cells one (cell, action) can lead to at a fidelity.

``rnhql aliasing SCENARIO --fidelity NAME --out DIR`` (or ``python -m
scenarios.studies.ladder.aliasing``): the measurement is :func:`scenarios.api.aliasing`
(:mod:`sim.physics.models.aliasing`: every action from every cell that reaches G,
``--repeats`` times, from the poses the robot can be in at that fidelity). Written to
``DIR``: ``aliasing.json`` (``multi_outcome_fraction``: share of (cell, action) pairs with
more than one next cell; ``mean_entropy_bits`` of the next-cell distribution;
``bump_probability`` and the outcome counts per pair), ``aliasing.png`` (a heat map of
each cell's largest next-cell entropy over its four actions) and ``aliasing.rrd``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import rerun as rr

from scenarios.artifacts import load_artifact, write_artifact
from scenarios.figures.save import save_figure
from scenarios.recording.file import RecordingFile
from scenarios.script_args import (
    arg,
    artifact_arg,
    command_line,
    parse,
    parser_of,
    positional,
)
from scenarios.values import Aliasing
from sim.files import atomic_write_text


def heat_map_figure(grid: np.ndarray, title: str, path: Path) -> None:
    """The heat map PNG: each cell's largest next-cell entropy (grey: blocked or not
    reaching G)."""
    matplotlib.use("Agg")

    fig, ax = plt.subplots(figsize=(6, 5.4))
    cmap = plt.get_cmap("magma").with_extremes(bad="0.75")  # blocked / not reaching G: grey
    im = ax.imshow(grid, origin="lower", cmap=cmap, vmin=0.0,
                   vmax=max(1.0, float(np.nanmax(grid)) if np.isfinite(grid).any() else 1.0))
    fig.colorbar(im, ax=ax, label="largest next-cell entropy over the 4 actions [bits]")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x [cells]  (grey: blocked or not reaching G)")
    ax.set_ylabel("y [cells]")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def write_artifact_of(name: str, command: str, result: Aliasing) -> None:
    """``docs/results/aliasing.NAME.json``: the summary figures and the heat map's cells
    (None: blocked or not reaching G), what the docs' table and figure are drawn from."""
    keep = ("scenario", "fidelity", "repeats", "seed", "pairs", "primitives",
            "multi_outcome_fraction", "mean_entropy_bits", "mean_bump_probability")
    data = {k: result.record[k] for k in keep}
    data["heat_map"] = [[None if np.isnan(v) else round(float(v), 4) for v in row]
                        for row in result.heat_map]
    write_artifact(f"aliasing.{name}", command, ["physics-exact", "physics-noisy"], data,
                   study=__file__)


def figure_from_artifact(name: str, path: Path) -> None:
    """Redraw the heat map from artifact ``name`` (``rnhql report --figures``)."""
    d = load_artifact(name)["data"]
    grid = np.array([[np.nan if v is None else v for v in row] for row in d["heat_map"]])
    heat_map_figure(grid, f"{d['scenario']}, fidelity {d['fidelity']}: "
                    f"{100 * d['multi_outcome_fraction']:.1f} % of (cell, action) pairs alias",
                    path)


def write_outputs(out: Path, result: Aliasing) -> None:
    """``aliasing.json`` (every pair's next cells), the heat map PNG and a recording."""
    matplotlib.use("Agg")

    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "aliasing.json", json.dumps(dict(result.record), indent=1))
    grid = result.heat_map
    heat_map_figure(grid, f"{result.scenario}, fidelity {result.fidelity}: "
                    f"{100 * result.multi_outcome_fraction:.1f} % of (cell, action) pairs "
                    "alias", out / "aliasing.png")
    cmap = plt.get_cmap("magma").with_extremes(bad="0.75")
    with RecordingFile(out / "aliasing.rrd",
                       recording_name=f"aliasing {result.scenario} {result.fidelity}") as rec:
        vmax = max(1.0, float(np.nanmax(grid)) if np.isfinite(grid).any() else 1.0)
        rgba = cmap(np.ma.masked_invalid(np.flipud(grid)) / vmax)  # the PNG's colours
        rec.stream.log("aliasing/entropy_map",
                       rr.Image((255 * rgba[..., :3]).astype(np.uint8)))
        rec.stream.log("aliasing/summary", rr.TextDocument(
            f"fidelity {result.fidelity}: multi_outcome_fraction "
            f"{result.multi_outcome_fraction:.4f}, mean entropy "
            f"{result.mean_entropy_bits:.4f} bits, mean bump probability "
            f"{result.mean_bump_probability:.4f} ({result.repeats} drives per pair). "
            "Map: each cell's largest next-cell entropy over its 4 actions, 0 (black) to "
            f"{vmax:g} bits (yellow); grey: blocked or not reaching G."))


@dataclass(frozen=True)
class Args:
    scenario: str = positional("a built-in name, a .toml or a .map (with --start/--goal)")
    out: str = arg(None, "output folder: aliasing.json, heat map PNG, recording (required)",
                   metavar="DIR", required=True)
    fidelity: str = arg("exact", "exact (default), a preset (noisy, slippery, uncalibrated, "
                        "open-loop, localised) or knobs")
    repeats: int = arg(20, "drives per (cell, action)")
    seed: int = arg(0, "noise and start-pose seed")
    rewards: str | None = arg(None, "reward scheme (does not change aliasing)")
    artifact: str | None = artifact_arg("aliasing")


def main(argv: list[str] | None = None) -> int:
    from scenarios import api

    parser = parser_of(Args, __doc__)
    args = parse(Args, __doc__, argv)
    result = api.aliasing(args.scenario, fidelity=args.fidelity, repeats=args.repeats,
                          seed=args.seed, rewards=args.rewards)
    report(result, Path(args.out), args.artifact,
           command_line("rnhql aliasing", parser, args))
    return 0


def report(result: Aliasing, out: Path, artifact: str | None, command: str) -> None:
    """Write ``out`` (and the artifact, whose command is ``command``) and say what it found."""
    write_outputs(out, result)
    if artifact:
        write_artifact_of(artifact, command, result)
    print(f"{result}; wrote {out}/aliasing.json, aliasing.png, aliasing.rrd")


if __name__ == "__main__":
    raise SystemExit(main())
