"""PNG figures of a comparison: the paper's curves and the learned routes on the map.

Curves are the median over seeds with an interquartile band, smoothed by a
moving average (window in the legend) because single-episode steps are noisy.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from learning.methods.registry import shown_name
from learning.metrics import windowed_reward_per_step
from scenarios.figures.mpl import pyplot
from scenarios.figures.save import save_figure
from scenarios.palette import method_colour_mpl
from sim.grid import TabularModel
from sim.grid.planning import bfs_route
from sim.scenario import Scenario

if TYPE_CHECKING:
    from matplotlib.axes import Axes


def _smooth(y: np.ndarray, window: int) -> np.ndarray:
    if window <= 1 or y.shape[-1] < window:
        return y
    kernel = np.ones(window) / window
    return np.apply_along_axis(lambda r: np.convolve(r, kernel, mode="valid"), -1, y)


def _groups(results: dict[str, Any]) -> dict[tuple[str, str], list[dict[str, Any]]]:
    out: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in results["runs"]:
        out.setdefault((r["method"], r["world"]), []).append(r)
    return out


def _series(run: dict[str, Any], key: str, window: int) -> np.ndarray:
    """A run's curve, smoothed over ``window`` episodes.

    Reward per step is the ratio of sums over the window (total return / total
    steps), never a mean of per-episode ratios that one-step episodes would spike.
    """
    if key == "reward_per_step":
        return windowed_reward_per_step(np.asarray(run["return_per_episode"]),
                                        np.asarray(run["steps_per_episode"]),
                                        window)[window - 1:]
    return _smooth(np.asarray(run[key], dtype=float), window)


def curve_figure(results: dict[str, Any], key: str, ylabel: str, path: Path,
                 window: int = 25, logy: bool = False, what: str = "") -> None:
    """Median and IQR over seeds of a per-episode figure; ``what`` says which episodes it
    counts (the training ones start on random cells: they are not the ranked test)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    n_episodes = len(results["runs"][0]["steps_per_episode"])
    window = min(window, n_episodes)
    for (method, world), runs in _groups(results).items():
        y = np.array([_series(r, key, window) for r in runs])
        x = np.arange(y.shape[1]) + (window // 2 if y.shape[1] < n_episodes else 0)
        q25, med, q75 = np.percentile(y, [25, 50, 75], axis=0)
        name = shown_name(method)
        label = name if len({w for _, w in _groups(results)}) == 1 else f"{name} ({world})"
        colour = method_colour_mpl(method)
        ax.plot(x, med, color=colour, lw=1.4, label=label,
                ls="-" if world == "grid" else "--")
        ax.fill_between(x, q25, q75, color=colour, alpha=0.15, lw=0)
    ax.set_xlabel("episode")
    ax.set_ylabel(ylabel)
    if logy:
        ax.set_yscale("log")
    rw = results["scenario"].get("rewards")
    scheme = f", rewards {rw['scheme']}" if rw else ""
    ax.set_title(f"{results['scenario']['name']}{scheme}: {ylabel} (median, IQR over seeds; "
                 f"window {window})" + (f"\n{what}" if what else ""), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def training_starts(results: dict[str, Any]) -> str:
    """How the training episodes start, for a curve's title."""
    share = results["scenario"].get("s_start_share") or 0.0
    if share > 0:
        return (f"training episodes, {share:.0%} from S and the rest from random cells (the "
                "ranking reads the greedy test from S: greedy_test.png)")
    return ("training episodes from random cells, not the greedy test from S that the ranking "
            "reads (greedy_test.png)")


def optimal_share(runs: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """(test episodes, share of seeds whose greedy route from S was optimal at that test),
    over the tests every run has."""
    n = min(len(r["test_episodes"]) for r in runs)
    episodes = np.asarray(runs[0]["test_episodes"][:n])
    hits = np.array([[length == r["optimal_route_length"] for length in
                      r["test_route_length"][:n]] for r in runs], dtype=float)
    return episodes, hits.mean(axis=0)


def greedy_test_figure(results: dict[str, Any], path: Path) -> None:
    """What the ranking reads: per method, the share of seeds whose greedy route from S is
    optimal at each test (every ``test_every`` episodes); a method is stably optimal in a
    seed from the test after which that seed's line never drops again."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    groups = _groups(results)
    several_worlds = len({w for _, w in groups}) > 1
    for (method, world), runs in groups.items():
        x, share = optimal_share(runs)
        label = f"{shown_name(method)} ({world})" if several_worlds else shown_name(method)
        ax.step(x, share, where="post", color=method_colour_mpl(method), lw=1.6, label=label,
                ls="-" if world == "grid" else "--", alpha=0.85)
    ax.set_xlabel("episodes trained")
    ax.set_ylabel("seeds whose greedy route from S is optimal")
    ax.set_ylim(-0.03, 1.03)
    rw = results["scenario"].get("rewards")
    scheme = f", rewards {rw['scheme']}" if rw else ""
    n = max(len(runs) for runs in groups.values())
    ax.set_title(f"{results['scenario']['name']}{scheme}: the greedy test from S (what the "
                 f"ranking reads)\nshare of the {n} seeds whose greedy route is optimal, at "
                 "each test", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def draw_map(ax: Axes, sc: Scenario, model: TabularModel) -> None:
    plt = pyplot()
    ax.imshow(model.blocked, origin="lower", cmap="Greys", alpha=0.25,
              extent=(0, sc.width_m, 0, sc.height_m), vmin=0, vmax=1.5)
    for o in sc.obstacles:
        ax.add_patch(plt.Circle((o.x_m, o.y_m), o.radius_m, color="#464a54", lw=0))
    c = sc.cell_size_m
    if sc.blocked_cells:  # one image, not a patch per cell (a 512² map has ~10^5 of them)
        walls = np.zeros((sc.ny, sc.nx))
        cells = np.asarray(sc.blocked_cells, dtype=np.int64)
        walls[cells[:, 1], cells[:, 0]] = 1.0
        ax.imshow(np.ma.masked_equal(walls, 0.0), origin="lower", interpolation="nearest",
                  cmap=plt.matplotlib.colors.ListedColormap(["#464a54"]),
                  extent=(0, sc.width_m, 0, sc.height_m),
                  vmin=0, vmax=1)
    for cell, colour, label in ((sc.start, "#2ea043", "S"), (sc.goal, "#e6aa14", "G")):
        x, y = (cell[0] + 0.5) * c, (cell[1] + 0.5) * c
        ax.plot(x, y, "o", color=colour, ms=8, zorder=5)
        ax.annotate(label, (x, y), xytext=(4, 4), textcoords="offset points", fontsize=9,
                    weight="bold")
    ax.set_xlim(0, sc.width_m)
    ax.set_ylim(0, sc.height_m)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def routes_figure(results: dict[str, Any], sc: Scenario, model: TabularModel,
                  path: Path) -> None:
    """One panel per method (and world): seed-0's final greedy route against the BFS optimum."""
    plt = pyplot()
    groups = _groups(results)
    n = len(groups)
    cols = min(n, 3)
    rows = int(np.ceil(n / cols))
    plt = pyplot()
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 4 * rows), dpi=100, squeeze=False)
    optimum = model.coords[bfs_route(model.next_state, model.distance_to_goal, model.start)]
    for ax, ((method, world), runs) in zip(axes.ravel(), groups.items(), strict=False):
        draw_map(ax, sc, model)
        ax.plot(optimum[:, 0], optimum[:, 1], color="#888888", lw=3, alpha=0.5,
                label=f"BFS optimum ({len(optimum) - 1})")
        run = min(runs, key=lambda r: r["seed"])
        route = model.coords[np.asarray(run["final_route"], dtype=int)]
        length = run["final_route_length"]
        ax.plot(route[:, 0], route[:, 1], color=method_colour_mpl(method), lw=1.6,
                label=f"greedy route ({'G not reached' if length < 0 else length})")
        ax.set_title(f"{method} ({world}), seed {run['seed']}", fontsize=9)
        # below the map, never over its obstacles
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.01), ncol=2,
                  frameon=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def time_figure(results: dict[str, Any], path: Path) -> None:
    """Execution time per episode (the paper's Fig. 10), median over seeds."""
    curve_figure(results, "wall_time_per_episode_s", "wall time per episode [s]", path,
                 window=50, logy=True)


def all_figures(results: dict[str, Any], sc: Scenario, model: TabularModel,
                out_dir: Path) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = [out_dir / "steps_per_episode.png", out_dir / "reward_per_step.png",
             out_dir / "time_per_episode.png", out_dir / "routes.png",
             out_dir / "greedy_test.png"]
    for p in paths:  # the tool's own names: a link planted there is replaced, not followed
        if p.is_symlink():
            p.unlink()
    starts = training_starts(results)
    curve_figure(results, "steps_per_episode", "steps per episode", paths[0], logy=True,
                 what=starts)
    curve_figure(results, "reward_per_step", "reward per step (total return / total steps)",
                 paths[1], what=starts)
    time_figure(results, paths[2])
    routes_figure(results, sc, model, paths[3])
    greedy_test_figure(results, paths[4])
    return paths
