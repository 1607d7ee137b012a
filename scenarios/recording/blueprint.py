"""The default layouts a recording opens with: one run, a saved agent's route, a comparison.

What the panels show is logged by :mod:`scenarios.recording.scene` and the recorder;
this module only arranges it. Rules kept by every layout (each a complaint once):

* a plot's legend never sits on its curves: a single run's plots name their series in
  the title by colour, and a comparison's key is a panel of its own;
* a title shows whole at the default size (short enough for its panel's width);
* a curve panel spans the whole run (:func:`whole_run`);
* a physics run says, beside its map, which timeline plays the continuous drive.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import rerun.blueprint as rrb

from scenarios.recording.scene import (
    BACKGROUND,
    METRICS,
    SUCCESS_WINDOW,
    SUMMARY_FIGURES,
    path,
    potential_names,
)
from sim.scenario import Scenario


def _bounds(sc: Scenario, pad: float = 0.5) -> rrb.VisualBounds2D:
    # in the view's (flipped) frame y runs from -height (top) to 0 (bottom); a strip of
    # room is left below the arena for the route labels and the colour key
    return rrb.VisualBounds2D(x_range=[-pad, sc.width_m + pad],
                              y_range=[-sc.height_m - pad, pad + 0.15 * sc.height_m])


def map_view(prefix: str, sc: Scenario, name: str = "Map: robot, trajectory, obstacles",
             legend: bool = True) -> rrb.Spatial2DView:
    w = path(prefix, "world")
    hide = [] if legend else [f"- /{w}/legend"]
    return rrb.Spatial2DView(origin=path(prefix, "") or "/", name=name,
                             contents=[f"+ /{w}/**", f"- /{w}/values/**", *hide],
                             background=BACKGROUND, visual_bounds=_bounds(sc))


def value_view(prefix: str, sc: Scenario, which: str, name: str) -> rrb.Spatial2DView:
    w = path(prefix, "world")
    extra = [f"+ /{w}/values/policy"] if which == "max_q" else []
    return rrb.Spatial2DView(
        origin=path(prefix, "") or "/", name=name, background=BACKGROUND,
        contents=[f"+ /{w}", f"+ /{w}/values/{which}/**", f"+ /{w}/values/mask",
                  f"+ /{w}/obstacles", f"+ /{w}/arena", f"+ /{w}/start", f"+ /{w}/goal",
                  *extra], visual_bounds=_bounds(sc))


def whole_run() -> rrb.TimeAxis:
    """A curve panel's x axis over the whole run: without it the viewer, which plays the
    recording on open, follows the time cursor and shows only the last ~1000 episodes,
    hiding the early learning where methods differ."""
    every = rrb.TimeRangeBoundary.infinite()
    return rrb.TimeAxis(view_range=rrb.TimeRange(start=every, end=every))


# a single run's plots: title (naming each series by its colour in
# scene.SERIES_COLOURS when there are several) and a fixed y range where one is known
PLOTS = {
    "steps": ("Training steps per episode, random starts (blue: the optimum from S)", None),
    "success": (f"Success rate, last {SUCCESS_WINDOW} (dots: 0/1)", (-0.05, 1.05)),
    "reward_per_step": (f"Reward per step (last {SUCCESS_WINDOW})", None),
    "return": ("Return", None),
    "shaping": ("Shaping F: mean, std", None),
    "wall_time": ("Wall time per episode [ms]", None),
    "policy": ("Share of cells whose greedy move is optimal", (-0.05, 1.05)),
}


def plot(prefix: str, which: str, name: str | None = None,
         legend: bool = False) -> rrb.TimeSeriesView:
    """A single run's plot ``which``; ``name`` replaces the title (a tab's short name), and
    then ``legend`` may name the series instead (top right, away from a falling curve)."""
    m = path(prefix, "metrics")
    title, y_range = PLOTS[which]
    ents = [f"+ /{m}/{e}" for e, (_, p) in METRICS.items() if p == which]
    return rrb.TimeSeriesView(name=name or title, contents=ents, axis_x=whole_run(),
                              axis_y=None if y_range is None else rrb.ScalarAxis(range=y_range),
                              plot_legend=rrb.PlotLegend(corner="RightTop", visible=legend))


def _panels(timeline: str = "episode") -> list[Any]:
    return [rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
            rrb.TimePanel(state="collapsed", timeline=timeline)]


def map_title(world: str = "grid", fidelity: str | None = None) -> str:
    """The map panel's title: what it shows, and in a physics run the fidelity in force."""
    if world != "physics":
        return "Map: robot, trajectory, obstacles"
    return f"Map · physics ({fidelity or 'exact'}): robot disc, trajectory, contacts"


def value_title(method: str | None) -> str:
    """The potential panel's title: the potential the method shapes with, by its name."""
    names = potential_names(method)
    return names[1] if names else f"{method or 'this method'}: no learned potential"


def map_column(prefix: str, sc: Scenario, world: str, fidelity: str | None) -> Any:
    """The map; in a physics run with the note on its timelines under it."""
    view = map_view(prefix, sc, map_title(world, fidelity))
    if world != "physics":
        return view
    note = rrb.TextDocumentView(origin="/" + path(prefix, "notes/drive"), name="Timelines")
    return rrb.Vertical(view, note, row_shares=[12, 1.4])


def route_blueprint(prefix: str, sc: Scenario, method: str | None = None,
                    world: str = "grid", fidelity: str | None = None) -> rrb.Blueprint:
    """A saved agent's route (``rnhql route --record``): only panels that have data (the map,
    the value maps and the run card; no training curves exist)."""
    right = rrb.Vertical(
        rrb.Horizontal(value_view(prefix, sc, "v_nn", value_title(method)),
                       value_view(prefix, sc, "max_q", "max_a Q + greedy policy")),
        rrb.TextDocumentView(origin=path(prefix, "meta") or "/meta", name="Run info"),
        row_shares=[3, 2])
    return rrb.Blueprint(rrb.Horizontal(map_view(prefix, sc, map_title(world, fidelity)),
                                        right, column_shares=[5, 4]), *_panels())


def run_blueprint(prefix: str, sc: Scenario, method: str | None = None, world: str = "grid",
                  fidelity: str | None = None) -> rrb.Blueprint:
    """One run: the map on the left; values, curves and the run card on the right."""
    p = path(prefix, "")
    right = rrb.Vertical(
        rrb.Horizontal(value_view(prefix, sc, "v_nn", value_title(method)),
                       value_view(prefix, sc, "max_q", "max_a Q + greedy policy")),
        plot(prefix, "steps"),
        rrb.Horizontal(plot(prefix, "success"), plot(prefix, "reward_per_step")),
        rrb.Tabs(plot(prefix, "return", "Return"), plot(prefix, "policy", "Policy"),
                 plot(prefix, "shaping", "Shaping F", legend=True),
                 plot(prefix, "wall_time", "Wall time"),
                 rrb.TextDocumentView(origin=path(prefix, "meta") or "/meta", name="Run info"),
                 rrb.TextLogView(origin=p or "/", name="Events")),
        row_shares=[3, 2, 2, 2])
    return rrb.Blueprint(rrb.Horizontal(map_column(prefix, sc, world, fidelity), right,
                                        column_shares=[5, 4]), *_panels())


def key_view(bounds: tuple[tuple[float, float], tuple[float, float]]) -> rrb.Spatial2DView:
    """The comparison's key (:func:`scenarios.recording.scene.log_comparison_key`)."""
    (x0, x1), (y0, y1) = bounds
    return rrb.Spatial2DView(origin="/key", name="Key", background=(255, 255, 255),
                             visual_bounds=rrb.VisualBounds2D(x_range=[x0, x1],
                                                              y_range=[y0, y1]))


def comparison_blueprint(runs: Sequence[tuple[str, int]], sc: Scenario, prefix_of: Any,
                         key: tuple[tuple[float, float], tuple[float, float]] | None = None
                         ) -> rrb.Blueprint:
    """Methods x seeds: one map per method (its first seed), and per method one median curve
    with its interquartile band (:mod:`scenarios.recording.summary`). The per-seed curves
    stay in the file under each run, out of the default views. With ``key`` (the bounds of
    the logged key), a key panel beside the curves names the maps' lines and the methods'
    colours, so no plot carries a legend over its curves."""
    methods: list[str] = []
    for m, _ in runs:
        if m not in methods:
            methods.append(m)
    first = {m: min(s for mm, s in runs if mm == m) for m in methods}
    maps = [map_view(prefix_of(m, first[m]), sc, name=f"{m} (seed {first[m]})", legend=False)
            for m in methods]
    curves = [rrb.TimeSeriesView(name=title, origin=f"/summary/{fig}", axis_x=whole_run(),
                                 plot_legend=rrb.PlotLegend(visible=key is None and i == 0))
              for i, (fig, title) in enumerate(SUMMARY_FIGURES.items())]
    grid = rrb.Grid(*curves, grid_columns=2)
    row = rrb.Horizontal(key_view(key), grid, column_shares=[2.4, 6]) if key else grid
    return rrb.Blueprint(rrb.Vertical(rrb.Grid(*maps), row, row_shares=[3, 2]), *_panels())
