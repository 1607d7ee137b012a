"""Every figure in ``docs/``: the artifacts it is drawn from and how, or the recording it
is a screenshot of.

A result figure is redrawn from committed artifacts (:mod:`scenarios.artifacts`) by
``rnhql report --figures``, never from a study's scratch folder, so the figure and the
generated table beside it show the same numbers; ``rnhql report`` marks a figure stale
when one of its artifacts is. A screenshot of the Rerun viewer is not a measurement: it
names the command that wrote the recording and how the screenshot was taken.
``tests/test_artifact_figures.py`` checks that every ``docs/*.png`` is one or the other.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from scenarios.artifacts import ROOT, ArtifactError, load_artifact


@dataclass(frozen=True)
class ArtifactFigure:
    """A ``docs/`` figure drawn from ``artifacts`` by ``drawer``, named ``module:function``
    and called as ``function(*artifacts, path=path)``. The study module is imported when the
    figure is drawn: a study loads matplotlib (about 270 ms) and its own dependencies,
    which `rnhql report` without --figures and the docs' Cog run never use."""

    path: str  # relative to the repository root
    artifacts: tuple[str, ...]
    drawer: str

    def draw(self, path: Path) -> object:
        module, function = self.drawer.split(":")
        return getattr(importlib.import_module(module), function)(*self.artifacts, path=path)


@dataclass(frozen=True)
class Screenshot:
    """A ``docs/`` picture of the Rerun viewer showing the recording ``command`` writes."""

    path: str
    command: str


JUDGING = ("heldout.judging-256", "heldout.judging-512")
FRESH = ("heldout.fresh-256", "heldout.fresh-512")  # the fresh judging set
SCALING_MAPS = tuple(f"scaling-maps.{n}" for n in ("small", "seed7", "512"))
FIGURES = (
    ArtifactFigure("docs/scaling.png", ("scaling.arenas",),
                   "scenarios.studies.paper.scaling:figure_from_artifact"),
    ArtifactFigure("docs/scaling-maps.png", SCALING_MAPS,
                   "scenarios.studies.maps.scaling_maps_figure:figure_from_artifacts"),
    ArtifactFigure("docs/ablation.png", ("ablation.suite",),
                   "scenarios.studies.maps.ablation:figure_from_artifact"),
    ArtifactFigure("docs/ladder.png", ("ladder.study",),
                   "scenarios.studies.ladder.continuous_vs_grid:figure_from_artifact"),
    ArtifactFigure("docs/warm-start.png", ("warm-start.study",),
                   "scenarios.studies.ladder.warm_start:figure_from_artifact"),
    ArtifactFigure("docs/aliasing-noisy.png", ("aliasing.paper-50-noisy",),
                   "scenarios.studies.ladder.aliasing:figure_from_artifact"),
    ArtifactFigure("docs/physics_batch.png", ("physics-batch.this-machine",),
                   "scenarios.bench.physics_batch:figure_from_artifact"),
    ArtifactFigure("docs/heldout-profiles.png", JUDGING,
                   "scenarios.studies.maps.ranking:figure_from_artifact"),
    ArtifactFigure("docs/heldout-fresh-profiles.png", FRESH,
                   "scenarios.studies.maps.ranking:figure_from_artifact"),
    ArtifactFigure("docs/growth.png", ("growth.open-s10",),
                   "scenarios.studies.maps.growth:figure_from_artifact"),
)

SCREENSHOTS = (
    Screenshot("docs/recording.png", "rnhql train paper-50 --method rnh-ql+ --record"),
    Screenshot("docs/comparison.png", "rnhql compare paper-50 --rewards goal-only --seeds 10 "
               "--episodes 3000 --out results/paper-50 --record"),
    Screenshot("docs/physics-recording.png", "rnhql train paper-50 --method rnh-ql+ --world "
               "physics --fidelity noisy --episodes 200 --rewards goal-only --record "
               "recordings/physics-noisy.rrd"),
)

SCREENSHOT_HOW = ("python ../shared/tools/rrd_screenshot.py RECORDING.rrd docs/NAME.png "
                  "(serves the recording to Rerun's web viewer and screenshots it)")


def redraw(figures: tuple[ArtifactFigure, ...] = FIGURES
           ) -> tuple[list[Path], list[tuple[str, str]]]:
    """Redraw every figure whose artifacts load: the paths written, and (figure, why) for
    each one left as it was (a missing or malformed artifact, named)."""
    done, skipped = [], []
    for fig in figures:
        try:
            for name in fig.artifacts:
                load_artifact(name)
        except ArtifactError as err:
            skipped.append((fig.path, str(err)))
            continue
        path = ROOT / fig.path
        fig.draw(path)
        done.append(path)
    return done, skipped
