"""What a recording looks like: colours, the static scene, metadata and the blueprints.

Used by :mod:`scenarios.recording.recorder` (the API); see its docstring for the entity
paths and timelines. Everything spatial lives under ``<prefix>/world`` in metres,
x right and y up; a static ``Transform3D(scale=[1, -1, 1])`` at ``<prefix>/world``
turns the viewer's y-down 2-D views the right way up (views are rooted above it,
so the flip applies; text labels are not mirrored).
"""

from __future__ import annotations

import json
import subprocess
from collections.abc import Sequence
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from scenarios.palette import method_colour  # noqa: F401  (one colour per method, PNGs too)
from sim.grid import TabularModel
from sim.grid.planning import bfs_route
from sim.scenario import Scenario

# ---- colours (RGB / RGBA); obstacles dark, free light, route and robot distinct
BACKGROUND = (250, 250, 247)
WALL = (30, 30, 35)
GRID = (222, 222, 222)
INFLATED = (214, 218, 230, 255)  # free space the robot's disc cannot enter
OBSTACLE = (62, 66, 78)
START = (46, 160, 67)
GOAL = (230, 160, 20)
BFS_ROUTE = (40, 110, 235)
TRAIN = (245, 120, 30)  # training trajectory
TRAIN_VISITED = (252, 212, 170)  # opaque: 2-D points do not blend
GREEDY = (150, 60, 200)  # greedy test trajectory
GREEDY_VISITED = (222, 200, 238)
ROBOT = (220, 30, 40)
CONTACT = (255, 0, 160)
POLICY_OK = (20, 140, 60)  # greedy action follows a shortest route
POLICY_BAD = (220, 40, 40)
ROUTE_PALETTE = ((0, 160, 160), (200, 40, 140), (90, 90, 90), (120, 80, 20))
# ---- draw order (higher is on top)
Z_HEAT, Z_OCC, Z_GRID, Z_VISITED, Z_ROUTE, Z_TRAJ = -30.0, -20.0, -15.0, -10.0, 5.0, 10.0
Z_OBST, Z_SG, Z_POLICY, Z_CONTACT, Z_ROBOT, Z_HEADING = 20.0, 25.0, 28.0, 30.0, 40.0, 45.0

SUCCESS_WINDOW = 50  # episodes in the moving success rate
SUMMARY_WINDOW = 50  # episodes per window of a comparison's summary curves
SUMMARY_FIGURES = {  # figure -> view title (scenarios.recording.summary)
    "steps": "Steps per episode", "success": f"Success rate (last {SUMMARY_WINDOW} episodes)",
    "reward_per_step": f"Reward per step (total return / total steps, last {SUMMARY_WINDOW})"}
KIND_STYLE = {"train": (TRAIN, TRAIN_VISITED), "greedy-test": (GREEDY, GREEDY_VISITED)}
METRICS = {  # entity under <prefix>/metrics -> (series name, plot)
    "steps/episode": ("steps", "steps"), "steps/optimal": ("BFS optimum", "steps"),
    "success": ("success (0/1)", "success"), "success_rate": ("success rate", "success"),
    "return": ("return", "return"),
    "reward_per_step": (f"reward / step (last {SUCCESS_WINDOW})", "reward_per_step"),
    "wall_time_ms": ("wall time [ms]", "wall_time"),
    "shaping/mean": ("shaping F mean", "shaping"), "shaping/std": ("shaping F std", "shaping"),
    "policy_optimal": ("cells whose greedy move is optimal", "success"),
}


def path(prefix: str, rest: str) -> str:
    return f"{prefix}/{rest}" if prefix else rest


def kind_part(kind: str) -> str:
    return {"train": "train", "greedy-test": "greedy"}.get(kind, rr.escape_entity_path_part(kind))


# ------------------------------------------------------------------ metadata


def git_commit(cwd: Path | None = None) -> str | None:
    """HEAD of the repository holding this file (``+dirty`` if modified), or None."""
    cwd = cwd or Path(__file__).resolve().parent
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=cwd, capture_output=True,
                              text=True, timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=cwd, capture_output=True, text=True, timeout=5).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("+dirty" if dirty else "") if head else None


def versions() -> dict[str, str]:
    try:
        rnhql = metadata.version("rnhql")
    except metadata.PackageNotFoundError:
        rnhql = "unknown"
    return {"rnhql": rnhql, "rerun-sdk": rr.__version__}


def run_metadata(sc: Scenario, model: TabularModel, *, method: str, config: dict[str, Any],
                 seed: int, world: str) -> dict[str, Any]:
    return {**versions(), "git_commit": git_commit() or "unknown", "scenario": sc.name,
            "scenario_source": sc.source, "rewards": sc.rewards.label(), "method": method,
            "seed": seed, "world": world,
            "optimal_route_moves": model.optimal_route_length,
            "started_utc": datetime.now(UTC).isoformat(timespec="seconds"),
            "config": config}


def meta_markdown(meta: dict[str, Any], sc: Scenario, prefix: str) -> str:
    rows = "\n".join(f"| {k} | `{v}` |" for k, v in meta.items() if k != "config")
    cfg = json.dumps(meta["config"], indent=2, sort_keys=True, default=str)
    p = path(prefix, "")
    title = (f"{meta['method']} on {sc.name} (seed {meta['seed']}, {meta['world']} world, "
             f"rewards {sc.rewards.scheme})")
    return f"""# rnhql run: {title}

{sc.description}

| field | value |
|---|---|
{rows}

## Config
```json
{cfg}
```

## How to read this recording
* **Map**: dark discs are obstacles (true radii), blue-grey cells are blocked for the robot's
  disc (radius + clearance), green S / amber G are start and goal, the blue line is the BFS
  shortest route. Orange is a training episode, purple a greedy test from S; dots mark the
  cells it visited, pink points are contacts (bumps). The red disc ("robot" in the key) and its
  red arrow are the robot and its heading.
* **Timelines**: `episode` is the training episode (curves, heatmaps, the latest recorded
  trajectory). `step` plays the recorded episodes back to back, one row per move
  (`sim_time` does the same in simulated seconds for the physics world).
* **Values**: V_NN (upper-layer RBF network) and max_a Q over the free cells, colour-mapped
  with viridis (dark low, yellow high; hover a cell for its value, shown as "depth").
  Arrows are the greedy action: green where it is a shortest-route move, red where not.
* Entities live under `{p or '/'}`.
"""


# ------------------------------------------------------------------ static scene


def occupancy_rgba(sc: Scenario, model: TabularModel, free: tuple[int, ...]) -> np.ndarray:
    """uint8[ny, nx, 4], row iy (y up after the world flip): blocked cells over ``free``."""
    img = np.empty((model.ny, model.nx, 4), dtype=np.uint8)
    img[:] = free
    img[model.blocked] = INFLATED
    for ix, iy in sc.blocked_cells:
        img[iy, ix] = (*OBSTACLE, 255)
    return img


def grid_lines(sc: Scenario) -> list[np.ndarray]:
    c, w, h = sc.cell_size_m, sc.width_m, sc.height_m
    xs = [np.array([[i * c, 0.0], [i * c, h]]) for i in range(1, sc.nx)]
    ys = [np.array([[0.0, j * c], [w, j * c]]) for j in range(1, sc.ny)]
    return xs + ys


def label_anchor(points: np.ndarray, avoid: Sequence[tuple[float, float]],
                 bounds: tuple[float, float, float, float], margin: float) -> np.ndarray:
    """Where a route's label goes: the route point farthest from S and G (so the text never
    sits on them), pulled at least ``margin`` inside the map (so it never runs off the view).

    Labels are drawn centred on their anchor; ``margin`` should be about half the label's
    width in map units.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    xmin, ymin, xmax, ymax = bounds
    centre = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2])
    cand = np.vstack([pts, centre]) if len(pts) else centre[None, :]
    av = np.asarray(avoid, dtype=np.float64).reshape(-1, 2)
    far = np.min(np.linalg.norm(cand[:, None, :] - av[None, :, :], axis=2), axis=1)
    best = cand[int(np.argmax(far))]
    mx = min(margin, (xmax - xmin) / 2)
    my = 0.06 * (ymax - ymin)  # about one line of text
    return np.array([np.clip(best[0], xmin + mx, xmax - mx), np.clip(best[1], ymin + my,
                                                                       ymax - my)])


def route_points(model: TabularModel, states: Sequence[int] | np.ndarray) -> np.ndarray:
    return model.coords[np.asarray(states, dtype=np.int64)]


def log_scene(rec: rr.RecordingStream, prefix: str, sc: Scenario, model: TabularModel) -> None:
    """The static map: flip, walls, grid, occupancy, obstacles, start/goal, BFS route."""
    w = path(prefix, "world")
    c, wd, ht = sc.cell_size_m, sc.width_m, sc.height_m
    rec.log(w, rr.Transform3D(scale=[1.0, -1.0, 1.0]), static=True)
    rec.log(f"{w}/arena", rr.LineStrips2D([[[0, 0], [wd, 0], [wd, ht], [0, ht], [0, 0]]],
                                           radii=0.08 * c, colors=[WALL], draw_order=Z_OBST),
            static=True)
    rec.log(f"{w}/grid", rr.LineStrips2D(grid_lines(sc), radii=0.012 * c, colors=[GRID],
                                          draw_order=Z_GRID), static=True)
    rec.log(f"{w}/occupancy", rr.Transform3D(scale=[c, c, 1.0]),
            rr.Image(occupancy_rgba(sc, model, (*BACKGROUND, 255)), color_model="RGBA",
                     draw_order=Z_OCC), static=True)
    # the same cells over the heat maps: free cells transparent
    rec.log(f"{w}/values/mask", rr.Transform3D(scale=[c, c, 1.0]),
            rr.Image(occupancy_rgba(sc, model, (0, 0, 0, 0)), color_model="RGBA",
                     draw_order=Z_OCC), static=True)
    if sc.obstacles:
        circ = np.array([(o.x_m, o.y_m, o.radius_m) for o in sc.obstacles])
        rec.log(f"{w}/obstacles", rr.Points2D(circ[:, :2], radii=circ[:, 2], colors=[OBSTACLE],
                                              draw_order=Z_OBST), static=True)
    for name, cell, colour in (("start", sc.start, START), ("goal", sc.goal, GOAL)):
        xy = model.coords[cell[1] * model.nx + cell[0]]
        rec.log(f"{w}/{name}", rr.Points2D([xy], radii=0.45 * c, colors=[colour],
                                           labels=["S" if name == "start" else "G"],
                                           show_labels=True, draw_order=Z_SG), static=True)
    route = bfs_route(model.next_state, model.distance_to_goal, model.start)
    rec.log(f"{w}/routes/bfs", rr.LineStrips2D(
        [route_points(model, route)], radii=0.12 * c, colors=[BFS_ROUTE],
        labels=[f"BFS optimum: {len(route) - 1} moves"], show_labels=False,
        draw_order=Z_ROUTE), static=True)
    # a colour key below the arena
    keys = [("training episode", TRAIN), ("greedy test from S", GREEDY),
            (f"BFS shortest route ({len(route) - 1} moves)", BFS_ROUTE),
            ("contact / bump", CONTACT), ("robot", ROBOT)]
    xs = np.linspace(0.02, 0.82, len(keys)) * wd
    rec.log(f"{w}/legend", rr.Points2D(np.column_stack([xs, np.full(len(keys), -0.04 * ht)]),
                                       radii=0.35 * c, colors=[k[1] for k in keys],
                                       labels=[k[0] for k in keys], show_labels=True),
            static=True)
    # styles of the per-episode entities (static, so the columns carry data only)
    # the robot is named in the colour key, not on the map: a label riding on the robot
    # overlapped S at the start of every test (and G at its end)
    rec.log(f"{w}/robot", rr.Points2D.from_fields(radii=sc.robot.radius_m, colors=[ROBOT],
                                                  labels=["robot"], show_labels=False,
                                                  draw_order=Z_ROBOT), static=True)
    rec.log(f"{w}/robot", rr.Arrows2D.from_fields(radii=0.08 * c, colors=[ROBOT],
                                                  draw_order=Z_HEADING), static=True)
    for kind, (line, dots) in KIND_STYLE.items():
        k = f"{w}/{kind_part(kind)}"
        rec.log(f"{k}/trajectory", rr.LineStrips2D.from_fields(
            radii=0.07 * c, colors=[line], draw_order=Z_TRAJ), static=True)
        rec.log(f"{k}/visited", rr.Points2D.from_fields(radii=0.32 * c, colors=[dots],
                                                        draw_order=Z_VISITED), static=True)
        rec.log(f"{k}/contacts", rr.Points2D.from_fields(radii=0.18 * c, colors=[CONTACT],
                                                         draw_order=Z_CONTACT), static=True)
    rec.log(f"{w}/values/policy", rr.Arrows2D.from_fields(radii=0.13 * c,
                                                          draw_order=Z_POLICY), static=True)
    for name in ("v_nn", "max_q"):  # heat maps: one value per cell, scaled to metres
        rec.log(f"{w}/values/{name}", rr.Transform3D(scale=[c, c, 1.0]),
                rr.DepthImage.from_fields(meter=1.0, colormap="viridis", draw_order=Z_HEAT),
                static=True)
        rec.log(f"{w}/values/{name}/legend", rr.Points2D.from_fields(
            positions=[[model.nx / 2, -0.06 * model.ny]], radii=0.0, show_labels=True),
            static=True)


def log_series_styles(rec: rr.RecordingStream, prefix: str, *, label: str = "",
                      colour: tuple[int, int, int] | None = None) -> None:
    """Static names (and, for comparisons, one colour per method) of the metric series."""
    m = path(prefix, "metrics")
    for ent, (name, _) in METRICS.items():
        full = f"{label} {name}" if label else name
        kw: dict[str, Any] = {"names": [full]}
        if colour is not None:
            kw["colors"] = [colour]
        elif ent == "steps/optimal":
            kw["colors"] = [BFS_ROUTE]
        if ent in ("success",):
            rec.log(f"{m}/{ent}", rr.SeriesPoints(marker_sizes=[1.5], **kw), static=True)
        else:
            rec.log(f"{m}/{ent}", rr.SeriesLines(widths=[1.5], **kw), static=True)


# ------------------------------------------------------------------ blueprints


def _bounds(sc: Scenario, pad: float = 0.5) -> rrb.VisualBounds2D:
    # in the view's (flipped) frame y runs from -height (top) to 0 (bottom); a strip of
    # room is left below the arena for the legends
    return rrb.VisualBounds2D(x_range=[-pad, sc.width_m + pad],
                              y_range=[-sc.height_m - pad, pad + 0.12 * sc.height_m])


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


def plot(prefix: str, which: str, name: str) -> rrb.TimeSeriesView:
    m = path(prefix, "metrics")
    ents = [f"+ /{m}/{e}" for e, (_, p) in METRICS.items() if p == which]
    return rrb.TimeSeriesView(name=name, contents=ents, axis_x=whole_run(),
                              plot_legend=rrb.PlotLegend(corner="LeftTop"))


def _panels(timeline: str = "episode") -> list[Any]:
    return [rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
            rrb.TimePanel(state="collapsed", timeline=timeline)]


def map_title(world: str = "grid", fidelity: str | None = None) -> str:
    """The map panel's title: what it shows, and in a physics run the fidelity in force and
    the timeline that replays the drive at real speed."""
    if world != "physics":
        return "Map: robot, trajectory, obstacles"
    return (f"Map · physics ({fidelity or 'exact'}): robot disc, trajectory, contacts · "
            "timeline sim_time plays at real speed")


def value_title(method: str | None) -> str:
    """The upper-layer panel's title: what the method's potential is."""
    if method == "rnh-ql+":
        return "Phi: the optimistic model's value"
    if method == "rnh-ql+ablation":
        return "Phi: the optimistic model's value or V_NN (v_target)"
    return "V_NN (RBF upper layer)"


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
        plot(prefix, "steps", "Steps per episode vs BFS optimum"),
        rrb.Horizontal(plot(prefix, "success", "Success"),
                       plot(prefix, "reward_per_step", "Reward per step")),
        rrb.Tabs(plot(prefix, "return", "Return"), plot(prefix, "shaping", "Shaping F"),
                 plot(prefix, "wall_time", "Wall time"),
                 rrb.TextDocumentView(origin=path(prefix, "meta") or "/meta", name="Run info"),
                 rrb.TextLogView(origin=p or "/", name="Events")),
        row_shares=[3, 2, 2, 2])
    return rrb.Blueprint(rrb.Horizontal(map_view(prefix, sc, map_title(world, fidelity)),
                                        right, column_shares=[5, 4]), *_panels())


def comparison_blueprint(runs: Sequence[tuple[str, int]], sc: Scenario,
                         prefix_of: Any) -> rrb.Blueprint:
    """Methods x seeds: one map per method (its first seed), and per method one median curve
    with its interquartile band (:mod:`scenarios.recording.summary`). The per-seed curves
    stay in the file under each run, out of the default views."""
    methods: list[str] = []
    for m, _ in runs:
        if m not in methods:
            methods.append(m)
    first = {m: min(s for mm, s in runs if mm == m) for m in methods}
    maps = [map_view(prefix_of(m, first[m]), sc, name=f"{m} (seed {first[m]})", legend=False)
            for m in methods]
    curves = rrb.Horizontal(*[
        rrb.TimeSeriesView(name=f"{title}: median, IQR over seeds", origin=f"/summary/{fig}",
                           axis_x=whole_run(),
                           plot_legend=rrb.PlotLegend(corner="RightTop", visible=i == 0))
        for i, (fig, title) in enumerate(SUMMARY_FIGURES.items())])
    return rrb.Blueprint(rrb.Vertical(rrb.Grid(*maps), curves, row_shares=[3, 2]),
                         *_panels())
