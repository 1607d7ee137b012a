"""What a recording holds besides the runs' data: colours, the static scene, metadata, keys.

Used by :mod:`scenarios.recording.recorder` (the API; see its docstring for the entity
paths and timelines); the panels that show it are :mod:`scenarios.recording.blueprint`.
Everything spatial lives under ``<prefix>/world`` in metres, x right and y up; a static
``Transform3D(scale=[1, -1, 1])`` at ``<prefix>/world`` turns the viewer's y-down 2-D
views the right way up (views are rooted above it, so the flip applies; text labels are
not mirrored).
"""

from __future__ import annotations

import functools
import json
import subprocess
from collections.abc import Sequence
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr

from scenarios.palette import method_colour  # one colour per method, PNGs too
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
SUMMARY_FIGURES = {  # figure -> view title (scenarios.recording.summary); titles are kept
    # short enough to show whole in a third of a 1600-pixel window (about 36 characters)
    "greedy": "Greedy test from S: seeds optimal",
    "steps": "Training steps/episode: median, IQR",
    "success": f"Success (last {SUMMARY_WINDOW}): median, IQR",
    "reward_per_step": f"Reward/step (last {SUMMARY_WINDOW}): median, IQR"}
KIND_STYLE = {"train": (TRAIN, TRAIN_VISITED), "greedy-test": (GREEDY, GREEDY_VISITED)}
METRICS = {  # entity under <prefix>/metrics -> (series name, plot)
    "steps/episode": ("steps", "steps"), "steps/optimal": ("BFS optimum", "steps"),
    "success": ("success (0/1)", "success"), "success_rate": ("success rate", "success"),
    "return": ("return", "return"),
    "reward_per_step": (f"reward / step (last {SUCCESS_WINDOW})", "reward_per_step"),
    "wall_time_ms": ("wall time [ms]", "wall_time"),
    "shaping/mean": ("shaping F mean", "shaping"), "shaping/std": ("shaping F std", "shaping"),
    "policy_optimal": ("cells whose greedy move is optimal", "policy"),
}
SERIES_COLOURS = {  # a single run's series: the plot titles name them by these colours
    "steps/episode": (0, 140, 150), "steps/optimal": BFS_ROUTE,
    "success": (150, 150, 150), "success_rate": (20, 140, 60),
    "return": (110, 140, 30), "reward_per_step": (0, 140, 150), "wall_time_ms": (90, 90, 90),
    "shaping/mean": (150, 60, 200), "shaping/std": (245, 120, 30),
    "policy_optimal": (20, 140, 60)}
# the potential a method shapes with, as its value panel names it
# (learning.compiled.readout.potential)
POTENTIALS = {"rnh-ql": ("V_NN", "V_NN: the RBF upper layer"),
              "rnh-ql+": ("Φ", "Φ: the optimistic model's value"),
              "rnh-ql+ablation": ("Φ", "Φ: optimistic model's value or V_NN")}


def label_colour(label: str) -> tuple[int, int, int]:
    """The colour of a comparison's curve label (``haql``, ``haql-physics``): its method's."""
    return method_colour(label.split("-physics")[0].split("-grid")[0])


def path(prefix: str, rest: str) -> str:
    return f"{prefix}/{rest}" if prefix else rest


def kind_part(kind: str) -> str:
    return {"train": "train", "greedy-test": "greedy"}.get(kind, rr.escape_entity_path_part(kind))


# ------------------------------------------------------------------ metadata


@functools.lru_cache(maxsize=8)
def git_commit(cwd: Path | None = None) -> str | None:
    """HEAD of the repository holding this file (``+dirty`` if modified), or None. Asked
    once per process and folder: a comparison's recording opens one stream per run."""
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


def run_properties(meta: dict[str, Any], sc: Scenario, fidelity: str | None
                   ) -> dict[str, Any]:
    """The recording properties of a run (Rerun shows them per recording and the catalog
    lists them as ``property:rnhql:<field>`` columns): the fields a folder of recordings is
    filtered by first, then the rest of the metadata (the config as JSON)."""
    world = meta["world"]
    props: dict[str, Any] = {
        "kind": "run", "method": meta["method"], "seed": int(meta["seed"]), "world": world,
        "fidelity": fidelity or ("exact" if world == "physics" else "none (grid)"),
        "rewards": sc.rewards.scheme, "rewards_values": meta["rewards"],
        "scenario": meta["scenario"], "version": meta["rnhql"]}
    for k, v in meta.items():
        key = k.replace("-", "_")
        if k not in ("rnhql", "rewards", "fidelity") and key not in props:
            props[key] = v if isinstance(v, int | float | str) else json.dumps(v, default=str)
    return props


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
  The teal line is the final greedy route; its length is written under the map.
* **Timelines**: `episode` is the training episode (curves, heatmaps, the latest recorded
  trajectory). `step` plays the recorded episodes back to back, one row per move;
  `sim_time` (physics world) plays every physics step of the drive at real speed: pick it
  in the time panel's timeline menu.
* **Values**: the potential the method shapes with (V_NN, the RBF upper layer, for rnh-ql;
  Φ, the optimistic model's value, for rnh-ql+) and max_a Q over the free cells,
  colour-mapped with viridis (dark low, yellow high; hover a cell for its value, shown as
  "depth"). Arrows are the greedy action on every k-th cell, drawn k cells long: green
  where it is a shortest-route move, red where not.
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


def route_label_anchor(bounds: tuple[float, float, float, float], index: int) -> np.ndarray:
    """Where the ``index``-th route's label goes: centred just under the arena (the viewer
    draws a label's text below its anchor), above the colour key; a second route's under
    the key. Outside the arena a label never covers an obstacle, S, G or a route, whatever
    the map (inside it, text as wide as half a small map always did)."""
    xmin, ymin, xmax, ymax = bounds
    h = ymax - ymin
    return np.array([(xmin + xmax) / 2, ymin - (0.012 + 0.1 * index) * h])


ARROWS_ACROSS = 20  # policy arrows across the longer side of a map, at most


def policy_arrow_stride(model: TabularModel) -> int:
    """k: the policy arrows go on every k-th cell, k cells long, at most ``ARROWS_ACROSS``
    across the map, so each is readable at the value panel's default size (a 50-cell map
    in a ~215-pixel panel: k = 3, arrows ~10 pixels long; one per cell they were ~4 pixels,
    a grey texture)."""
    return max(1, -(-max(model.nx, model.ny) // ARROWS_ACROSS))


def potential_names(method: str | None) -> tuple[str, str] | None:
    """(short name, panel title) of the potential ``method`` shapes with, or None."""
    base = (method or "").split(" ", 1)[0]
    return POTENTIALS.get(base)


def key_positions(labels: Sequence[str], width: float, gap_chars: float = 4.0) -> np.ndarray:
    """x of each label's centre, in a row across ``width``: each label gets a share of the
    width in proportion to its length plus a gap."""
    share = np.array([len(t) + gap_chars for t in labels], dtype=float)
    return (np.cumsum(share) - share / 2) / share.sum() * width


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
    # a colour key below the arena and the route labels (route_label_anchor), each label
    # given room in proportion to its length (labels are centred on their dots; evenly
    # spaced dots let long labels overlap)
    keys = [("training episode", TRAIN), ("greedy test", GREEDY),
            (f"BFS optimum ({len(route) - 1} moves)", BFS_ROUTE),
            ("contact", CONTACT), ("robot", ROBOT)]
    xs = key_positions([k[0] for k in keys], wd)
    rec.log(f"{w}/legend", rr.Points2D(np.column_stack([xs, np.full(len(keys), -0.075 * ht)]),
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
    k = policy_arrow_stride(model)
    rec.log(f"{w}/values/policy", rr.Arrows2D.from_fields(radii=0.1 * c * k,
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
    """Static names and colours of the metric series: a single run's each in its own colour
    (:data:`SERIES_COLOURS`, which its plot titles name), a comparison's run in its method's."""
    m = path(prefix, "metrics")
    for ent, (name, _) in METRICS.items():
        full = f"{label} {name}" if label else name
        kw: dict[str, Any] = {"names": [full], "colors": [colour or SERIES_COLOURS[ent]]}
        if ent in ("success",):
            rec.log(f"{m}/{ent}", rr.SeriesPoints(marker_sizes=[1.5], **kw), static=True)
        else:
            rec.log(f"{m}/{ent}", rr.SeriesLines(widths=[1.5], **kw), static=True)


DRIVE_NOTE = ("**Watch the drive:** pick the `sim_time` timeline in the time panel's menu "
              "(bottom left, now `episode`) and press play: the robot drives every physics "
              "step at real speed. `episode` (the default) steps the curves and heat maps.")


def log_drive_note(rec: rr.RecordingStream, prefix: str) -> None:
    """A physics run's note on its timelines: the continuous drive is only on ``sim_time``,
    which the viewer does not pick by itself (the curves need ``episode``)."""
    rec.log(path(prefix, "notes/drive"), rr.TextDocument(DRIVE_NOTE, media_type="text/markdown"),
            static=True)


KEY_LINES = (("BFS shortest route", BFS_ROUTE), ("final greedy route", ROUTE_PALETTE[0]),
             ("last training episode", TRAIN), ("greedy test from S", GREEDY))
KEY_COLUMN = 2.8  # the key's two columns are centred at -/+ this (a row is 1 unit tall)
# under the key: a large comparison streams into the viewer for a minute or more, its
# curves empty until their data arrives, and nothing else says it is still loading
LOADING_NOTE = ("curves empty? a large recording", "takes a minute or more to load")


def log_comparison_key(rec: rr.RecordingStream, labels: Sequence[str]
                       ) -> tuple[tuple[float, float], tuple[float, float]]:
    """The comparison's key at ``key``, as coloured text: the maps' lines on the left,
    every method in its colour (its curves') on the right. Returns the (x, y) ranges it
    fills, for the key view's bounds: with a row a unit tall, the columns ~5.6 units
    apart keep ~20-character names apart at any panel size (the view keeps the aspect)."""
    left = [("maps:", WALL), *KEY_LINES]
    right = [("methods:", WALL), *[(lab, label_colour(lab)) for lab in labels]]
    n = max(len(left), len(right))
    note = [(text, WALL) for text in LOADING_NOTE]
    rows = left + right + note
    xy = np.array([(-KEY_COLUMN, i) for i in range(len(left))]
                  + [(KEY_COLUMN, i) for i in range(len(right))]
                  + [(0.0, n + 0.6 + i) for i in range(len(note))], dtype=float)
    rec.log("key", rr.Points2D(xy, radii=0.0, colors=[c for _, c in rows],
                               labels=[t for t, _ in rows], show_labels=True), static=True)
    half = 2 * KEY_COLUMN
    return (-half, half), (-0.8, n + len(note) + 0.8)
