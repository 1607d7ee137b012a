"""Text and PNG drawings of a greedy route next to the BFS optimum (``rnhql route``)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from scenarios.figures.mpl import pyplot
from scenarios.figures.plots import draw_map
from scenarios.figures.save import save_figure
from sim.grid import TabularModel
from sim.grid.planning import bfs_route
from sim.scenario import Scenario

LEGEND = "S start, G goal, * learned route, o optimum, @ both, # blocked, . free"


def ascii_routes(model: TabularModel, route: Sequence[int], optimum: Sequence[int]) -> str:
    """The map as text, top row first (y up), with both routes overlaid."""
    grid = np.where(model.blocked, "#", ".").astype("<U1").ravel()
    on_route = np.zeros(model.n_states, dtype=bool)
    on_route[np.asarray(route, dtype=int)] = True
    on_opt = np.zeros(model.n_states, dtype=bool)
    on_opt[np.asarray(optimum, dtype=int)] = True
    grid[on_opt] = "o"
    grid[on_route] = "*"
    grid[on_route & on_opt] = "@"
    grid[model.start], grid[model.goal] = "S", "G"
    rows = grid.reshape(model.ny, model.nx)[::-1]
    return "\n".join("".join(r) for r in rows) + "\n" + LEGEND


def route_png(sc: Scenario, model: TabularModel, route: Sequence[int], path: Path,
              title: str, trajectory: np.ndarray | None = None) -> None:
    """The map with the optimum, the learned grid route and (optionally) a driven trajectory."""
    plt = pyplot()

    optimum = model.coords[bfs_route(model.next_state, model.distance_to_goal, model.start)]
    pts = model.coords[np.asarray(route, dtype=int)]
    fig, ax = plt.subplots(figsize=(6, 6), dpi=110)
    draw_map(ax, sc, model)
    ax.plot(optimum[:, 0], optimum[:, 1], color="#888888", lw=4, alpha=0.5,
            label=f"BFS optimum ({len(optimum) - 1} moves)")
    ax.plot(pts[:, 0], pts[:, 1], color="#d9342b", lw=1.8,
            label=f"greedy route ({len(route) - 1} moves)")
    if trajectory is not None and len(trajectory):
        ax.plot(trajectory[:, 0], trajectory[:, 1], color="#3c78e6", lw=1.0,
                label="physics trajectory")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)
    plt.close(fig)
