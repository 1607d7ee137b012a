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

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from scenarios.artifacts import ROOT, ArtifactError, load_artifact


@dataclass(frozen=True)
class ArtifactFigure:
    """A ``docs/`` figure drawn by ``draw(path)`` from ``artifacts``."""

    path: str  # relative to the repository root
    artifacts: tuple[str, ...]
    draw: Callable[[Path], object]


@dataclass(frozen=True)
class Screenshot:
    """A ``docs/`` picture of the Rerun viewer showing the recording ``command`` writes."""

    path: str
    command: str


# Each figure's study is imported when it is drawn: a study loads matplotlib (about 270 ms)
# and its own dependencies, which `rnhql report` without --figures and the docs' Cog run
# never use.


def _scaling(path: Path) -> None:
    from scenarios.studies.paper.scaling import figure_from_artifact

    figure_from_artifact("scaling.arenas", path)


SCALING_MAPS = ("small", "seed7", "512")


def _scaling_maps(path: Path) -> None:
    from scenarios.studies.maps.scaling_maps_figure import draw, points_from_artifacts

    draw(points_from_artifacts(SCALING_MAPS), path)


def _ablation(path: Path) -> None:
    from scenarios.studies.maps.ablation import figure_from_artifact

    figure_from_artifact("ablation.suite", path)


def _ladder(path: Path) -> None:
    from scenarios.studies.ladder.continuous_vs_grid import figure_from_artifact

    figure_from_artifact("ladder.study", path)


def _aliasing(path: Path) -> None:
    from scenarios.studies.ladder.aliasing import figure_from_artifact

    figure_from_artifact("aliasing.paper-50-noisy", path)


def _physics_batch(path: Path) -> None:
    from scenarios.bench.physics_batch import figure_from_artifact

    figure_from_artifact("physics-batch.this-machine", path)


def _heldout_profiles(path: Path) -> None:
    from scenarios.studies.maps.ranking import figure_from_artifact

    figure_from_artifact(JUDGING, path)


JUDGING = ("heldout.judging-256", "heldout.judging-512")
FIGURES = (
    ArtifactFigure("docs/scaling.png", ("scaling.arenas",), _scaling),
    ArtifactFigure("docs/scaling-maps.png", tuple(f"scaling-maps.{n}" for n in SCALING_MAPS),
                   _scaling_maps),
    ArtifactFigure("docs/ablation.png", ("ablation.suite",), _ablation),
    ArtifactFigure("docs/ladder.png", ("ladder.study",), _ladder),
    ArtifactFigure("docs/aliasing-noisy.png", ("aliasing.paper-50-noisy",), _aliasing),
    ArtifactFigure("docs/physics_batch.png", ("physics-batch.this-machine",), _physics_batch),
    ArtifactFigure("docs/heldout-profiles.png", JUDGING, _heldout_profiles),
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
