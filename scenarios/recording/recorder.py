"""Rerun recordings of training runs: batched, columnar, safe to interrupt.

API (all arrays are numpy; nothing is logged per step)::

    rec = Recorder.create(path, scenario, model, method="rnh-ql", config=asdict(cfg), seed=0,
                          world="grid")          # metadata + static scene + blueprint
    rec.log_episode_trajectory(episode, states, poses=None, contacts=None, sim_time_s=None,
                               kind="train", contact_steps=None)
    rec.log_episode_metrics(episodes, steps, success, returns, reward_per_step=None,
                            wall_time_s=None, shaping_mean=None, shaping_std=None)
    rec.log_values(episode, q, greedy=None, v_nn=None)   # every K episodes
    rec.log_route("final route", states)                 # e.g. the final greedy route
    rec.close()                                          # idempotent; also `with Recorder...`

``states[k]`` is the state after ``k`` moves (``states[0]`` the start), so an
episode of ``n`` moves has ``n + 1`` states; ``poses`` (physics: x, y, heading
[m, m, rad]) and ``sim_time_s`` [s] have one row per state. In the grid world
poses come from ``model.coords`` and the heading from the last move.
``contacts`` are (k, 2) points [m] with optional ``contact_steps``; left out in
the grid world, the bumps (moves that left the state unchanged) are shown.

Cost: the ``log_*`` calls only copy arrays into a buffer; when
``flush_rows`` rows are pending or ``flush_interval_s`` has passed (and on
``close``), the buffer becomes one ``send_columns`` call per entity, built
vectorised over all buffered episodes (:mod:`scenarios.recording.batch`).
Measure with ``python -m scenarios.bench.recording``.

Files: :class:`RecordingFile` owns an explicit ``rr.RecordingStream`` writing to
``<path>.part``; ``close`` flushes, writes the footer and renames it to ``path``,
so a finished ``.rrd`` always passes ``rerun rrd verify``. Ctrl-C is a
``KeyboardInterrupt``: ``with`` blocks (and an ``atexit`` hook) close the file,
so an interrupted run leaves a verified recording of everything logged so far.
A hard kill (SIGKILL, power loss) leaves ``<path>.part`` without a footer; it
still opens in the viewer and passes ``rerun rrd verify --check-footers false``.

Entity paths and timelines: ``docs/recording.md`` (``P`` = ``prefix``, empty for a
single run; timelines ``episode``, ``step``, and ``sim_time`` in the physics world).

Comparisons (methods x seeds): each run is a subtree ``runs/<method>/s<seed>``
(:func:`run_prefix`); see :mod:`scenarios.recording.comparison`.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr

from learning.methods.registry import shown_name
from scenarios.recording import blueprint as layouts
from scenarios.recording import scene
from scenarios.recording.batch import EpisodeRecord, ValueFrame, send_episodes, send_values
from scenarios.recording.file import RecordingFile, rerun_cli, verify_recording
from sim.grid import TabularModel
from sim.grid.actions import ACTION_DELTAS
from sim.scenario import Scenario

__all__ = ["Recorder", "RecordingFile", "rerun_cli", "run_prefix", "verify_recording"]

SUCCESS_WINDOW = scene.SUCCESS_WINDOW


def run_prefix(method: str, seed: int) -> str:
    return f"runs/{rr.escape_entity_path_part(method)}/s{seed}"


def policy_arrow_cells(model: TabularModel, reachable: np.ndarray) -> tuple[int, np.ndarray]:
    """(k, the reachable cells on the lattice of every k-th cell): where the policy arrows
    go (:func:`scenarios.recording.scene.policy_arrow_stride`)."""
    k = scene.policy_arrow_stride(model)
    ix, iy = reachable % model.nx, reachable // model.nx
    on = (ix % k == k // 2) & (iy % k == k // 2)
    return k, reachable[on]


class Recorder:
    """Everything one training run logs; see the module docstring."""

    def __init__(self, file: RecordingFile, prefix: str, scenario: Scenario,
                 model: TabularModel, *, world: str, owns_file: bool,
                 flush_rows: int = 20_000, flush_interval_s: float = 5.0) -> None:
        self.file, self.stream, self.prefix = file, file.stream, prefix.strip("/")
        self.scenario, self.model, self.world = scenario, model, world
        self.method = ""  # set by create
        self.owns_file = owns_file
        self.flush_rows, self.flush_interval_s = flush_rows, flush_interval_s
        self._scalars: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}  # entity -> rows
        self._rows = 0
        self._last_flush = time.monotonic()
        self._step = 0  # next value of the `step` playback timeline
        self._sim = 0.0  # next value of `sim_time` [s]
        self._episodes: list[EpisodeRecord] = []
        self._values: list[ValueFrame] = []
        self._deltas = np.asarray(ACTION_DELTAS, dtype=np.float64) * model.cell_size_m
        self._success_tail = np.zeros(0)
        self._rps_tail = np.zeros((2, 0))  # returns, steps of the last episodes (reward/step)
        self.curve_stride = 1  # log every n-th episode's curves (curves-only runs: 10)
        self._free = np.flatnonzero(~model.blocked.ravel())
        self._reachable = np.flatnonzero(model.distance_to_goal > 0)
        self._arrow_stride, self._arrows = policy_arrow_cells(model, self._reachable)
        self._n_routes = 0
        self._pool: ThreadPoolExecutor | None = None
        self._pending: Future | None = None
        self.closed = False
        file._recorders.append(self)

    # ---------------------------------------------------------------- creation
    @classmethod
    def create(cls, path: str | Path | None, scenario: Scenario, model: TabularModel, *,
               method: str, config: dict[str, Any] | Any, seed: int, world: str = "grid",
               application_id: str = "rnhql", recording_name: str | None = None,
               prefix: str = "", file: RecordingFile | None = None,
               recording_id: str | None = None, blueprint: bool | str = True,
               with_scene: bool = True, fidelity: str | None = None,
               flush_rows: int = 20_000, flush_interval_s: float = 5.0) -> Recorder:
        """Open (or join ``file``) and log metadata, the static scene and the blueprint.

        ``config`` is a dict or a config dataclass. With ``file`` (a shared
        :class:`RecordingFile`) ``path`` is ignored and the run logs under ``prefix``.
        """
        if world not in ("grid", "physics"):
            raise ValueError(f"world must be 'grid' or 'physics', got {world!r}")
        owns = file is None
        if file is None:
            if path is None:
                raise ValueError("give a path or a shared RecordingFile")
            shown = world if fidelity is None else f"{world} ({fidelity})"
            name = recording_name or (f"{scenario.name} · {shown_name(method)} · s{seed} · "
                                      f"{shown}")
            file = RecordingFile(path, application_id=application_id,
                                 recording_id=recording_id, recording_name=name)
        rec = cls(file, prefix, scenario, model, world=world, owns_file=owns,
                  flush_rows=flush_rows, flush_interval_s=flush_interval_s)
        rec.method = method
        st = rec.stream
        if dataclasses.is_dataclass(config) and not isinstance(config, type):
            config = dataclasses.asdict(config)
        meta = scene.run_metadata(scenario, model, method=method, config=config, seed=seed,
                                  world=world)
        if fidelity is not None:
            meta["fidelity"] = fidelity
        st.log(rec._p("meta"), rr.TextDocument(scene.meta_markdown(meta, scenario, rec.prefix),
                                                media_type="text/markdown"), static=True)
        if not rec.prefix:  # a recording of its own: what a folder of them is filtered by
            st.send_property("rnhql", rr.AnyValues(**scene.run_properties(meta, scenario,
                                                                          fidelity)))
        if with_scene:  # a curves-only run in a comparison needs no map of its own
            scene.log_scene(st, rec.prefix, scenario, model)
            if world == "physics":
                scene.log_drive_note(st, rec.prefix)
        else:  # its per-seed curves stay in the file, every 10th episode (the comparison's
            rec.curve_stride = 10  # summary curves use every episode of every seed)
        if rec.prefix:  # one of several runs in a file: label and colour its curves
            scene.log_series_styles(st, rec.prefix, label=f"{shown_name(method)} s{seed}",
                                    colour=scene.method_colour(method))
        else:
            scene.log_series_styles(st, rec.prefix)
        if blueprint:  # True: a training run's; "route": a saved agent's route, no curves
            bp = (layouts.route_blueprint if blueprint == "route" else layouts.run_blueprint)
            st.send_blueprint(bp(rec.prefix, scenario, method, world, fidelity),
                              make_active=True, make_default=True)
        return rec

    def _p(self, rest: str) -> str:
        return scene.path(self.prefix, rest)

    # ---------------------------------------------------------------- buffering
    def _add_scalars(self, name: str, episodes: np.ndarray, values: np.ndarray) -> None:
        rows = (episodes, np.asarray(values, dtype=np.float64).reshape(-1))
        self._scalars.setdefault(self._p(f"metrics/{name}"), []).append(rows)
        self._rows += len(episodes)

    def _maybe_flush(self) -> None:
        if (self._rows >= self.flush_rows
                or time.monotonic() - self._last_flush >= self.flush_interval_s):
            self._flush_background()

    def _take(self) -> tuple[list[EpisodeRecord], list[ValueFrame], dict[str, list]]:
        """Hand over everything buffered and start a new buffer."""
        batch = (self._episodes, self._values, self._scalars)
        self._episodes, self._values, self._scalars = [], [], {}
        self._rows = 0
        self._last_flush = time.monotonic()
        return batch

    def _send(self, episodes: list[EpisodeRecord], frames: list[ValueFrame],
              scalars: dict[str, list]) -> None:
        """Build the columns and send them (one send_columns call per entity)."""
        if episodes:
            send_episodes(self.stream, self.prefix, self.model, self.world, episodes)
        if frames:
            names = scene.potential_names(self.method)
            send_values(self.stream, self.prefix, self.model, frames,
                        potential=names[0] if names else "potential")
        for entity, rows in scalars.items():
            self.stream.send_columns(
                entity, indexes=[rr.TimeColumn("episode",
                                               sequence=np.concatenate([r[0] for r in rows]))],
                columns=rr.Scalars.columns(scalars=np.concatenate([r[1] for r in rows])))

    def _flush_background(self) -> None:
        """Send the buffer from a worker thread while training goes on.

        The fused kernels release the GIL (``nogil``), so on a second core the
        column building overlaps training. One batch is in flight at a time:
        memory stays bounded and batches arrive in order.
        """
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rnhql-rec")
        batch = self._take()
        self._wait()
        self._pending = self._pool.submit(self._send, *batch)

    def _wait(self) -> None:
        if self._pending is not None:
            pending, self._pending = self._pending, None
            pending.result()  # re-raises an error from the worker

    def flush(self) -> None:
        """Send everything buffered now, after any batch still in flight."""
        self._wait()
        self._send(*self._take())

    # ---------------------------------------------------------------- per episode
    def log_episode_trajectory(self, episode: int, states: np.ndarray,
                               poses: np.ndarray | None = None,
                               contacts: np.ndarray | None = None,
                               sim_time_s: np.ndarray | None = None, kind: str = "train",
                               contact_steps: np.ndarray | None = None,
                               substeps: np.ndarray | None = None,
                               substep_times_s: np.ndarray | None = None) -> None:
        """One episode: robot per step, trajectory, visited cells, contacts, events.

        Only copies the arrays; the columns are built for many episodes at once
        when the buffer is flushed. ``contact_steps`` (one per contact, moves
        into the episode) places each contact's event on the ``step`` timeline.
        ``substeps`` (physics: every physics step's pose [m, m, rad]) with their
        ``substep_times_s`` (same clock as ``sim_time_s``) put the continuous drive
        on the ``sim_time`` timeline, playable at real speed.
        """
        states = np.array(states, dtype=np.int64)
        n = len(states)
        if n == 0:
            return
        if poses is not None:
            poses = np.array(poses, dtype=np.float64).reshape(-1, 3)
            if len(poses) != n:
                raise ValueError(f"poses has {len(poses)} rows, states {n}: one pose per state")
        t = None
        sim0 = self._sim
        if sim_time_s is not None:
            t = np.array(sim_time_s, dtype=np.float64)
            if len(t) != n:
                raise ValueError(f"sim_time_s has {len(t)} values, states {n}")
            self._sim += float(t[-1] - t[0]) + (float(t[-1] - t[-2]) if n > 1 else 0.0)
        if contacts is not None:
            contacts = np.array(contacts, dtype=np.float64).reshape(-1, 2)
            if contact_steps is not None:
                contact_steps = np.array(contact_steps, dtype=np.int64).reshape(-1)
                if len(contact_steps) != len(contacts):
                    raise ValueError("contact_steps needs one step per contact")
        sub = None
        if substeps is not None and t is not None and substep_times_s is not None:
            sp = np.array(substeps, dtype=np.float64).reshape(-1, 3)
            st = np.array(substep_times_s, dtype=np.float64).reshape(-1)
            if len(sp) != len(st):
                raise ValueError(f"substeps has {len(sp)} rows, substep_times_s {len(st)}")
            sub = (sp, sim0 + (st - t[0]))
        self._episodes.append(EpisodeRecord(int(episode), kind, states, poses, contacts,
                                            contact_steps, t, self._step, sim0, sub))
        self._step += n
        self._rows += n
        self._maybe_flush()

    def log_episode_metrics(self, episodes: np.ndarray, steps: np.ndarray,
                            success: np.ndarray, returns: np.ndarray,
                            reward_per_step: np.ndarray | None = None,
                            wall_time_s: np.ndarray | None = None,
                            shaping_mean: np.ndarray | None = None,
                            shaping_std: np.ndarray | None = None) -> None:
        """Per-episode curves on the `episode` timeline (a batch of consecutive episodes)."""
        ep = np.asarray(episodes, dtype=np.int64).reshape(-1)
        if len(ep) == 0:
            return
        given = {"steps": steps, "success": success, "returns": returns,
                 "reward_per_step": reward_per_step, "wall_time_s": wall_time_s,
                 "shaping_mean": shaping_mean, "shaping_std": shaping_std}
        for name, arr in given.items():
            if arr is not None and np.size(arr) != len(ep):
                raise ValueError(f"{name} has {np.size(arr)} values for {len(ep)} episodes")
        steps_f = np.asarray(steps, dtype=np.float64)
        succ = np.asarray(success, dtype=np.float64)
        ret = np.asarray(returns, dtype=np.float64)
        # reward per step: total return / total steps over the last SUCCESS_WINDOW episodes
        # (a per-episode ratio is all spikes from one-step episodes next to G)
        rs_hist = np.concatenate([self._rps_tail, np.stack([ret, steps_f])], axis=1)
        crs = np.concatenate([np.zeros((2, 1)), np.cumsum(rs_hist, axis=1)], axis=1)
        j = np.arange(self._rps_tail.shape[1], rs_hist.shape[1]) + 1
        jlo = np.maximum(j - SUCCESS_WINDOW, 0)
        tot = crs[1, j] - crs[1, jlo]
        rps = (np.divide(crs[0, j] - crs[0, jlo], tot, out=np.zeros(len(j)), where=tot > 0)
               if reward_per_step is None else np.asarray(reward_per_step, dtype=np.float64))
        self._rps_tail = rs_hist[:, -(SUCCESS_WINDOW - 1):]
        hist = np.concatenate([self._success_tail, succ])
        cs = np.concatenate([[0.0], np.cumsum(hist)])
        idx = np.arange(len(self._success_tail), len(hist)) + 1
        lo = np.maximum(idx - SUCCESS_WINDOW, 0)
        rate = (cs[idx] - cs[lo]) / (idx - lo)
        self._success_tail = hist[-(SUCCESS_WINDOW - 1):]
        series: dict[str, np.ndarray | None] = {
            "steps/episode": steps_f,
            "success": succ, "success_rate": rate, "return": ret, "reward_per_step": rps,
            "wall_time_ms": None if wall_time_s is None else 1e3 * np.asarray(wall_time_s),
            "shaping/mean": shaping_mean, "shaping/std": shaping_std}
        # the BFS optimum is a constant: the batch's first and last episodes draw its line
        ends = ep[[0, -1]] if len(ep) > 1 else ep
        self._add_scalars("steps/optimal", ends,
                          np.full(len(ends), float(self.model.optimal_route_length)))
        keep = slice(None) if self.curve_stride == 1 else (ep + 1) % self.curve_stride == 0
        for name, values in series.items():
            if values is not None and np.any(keep if isinstance(keep, np.ndarray) else True):
                self._add_scalars(name, ep[keep], np.asarray(values)[keep])
        self._maybe_flush()

    # ---------------------------------------------------------------- every K episodes
    def _heat(self, values: np.ndarray, value_range: tuple[float, float] | None
              ) -> tuple[np.ndarray, float, float]:
        m = self.model
        v = np.asarray(values, dtype=np.float64).reshape(-1)
        free_v = v[self._free]
        lo, hi = value_range or (float(free_v.min()), float(free_v.max()))
        hi = hi if hi > lo else lo + 1.0
        img = np.where(m.blocked.ravel(), lo, v).reshape(m.ny, m.nx).astype(np.float32)
        return img, lo, hi

    def log_values(self, episode: int, q: np.ndarray, greedy: np.ndarray | None = None,
                   v_nn: np.ndarray | None = None,
                   value_range: tuple[float, float] | None = None) -> None:
        """Heat maps of the method's potential (``v_nn``: V_NN of rnh-ql, Φ of rnh-ql+) and
        max_a Q, and the greedy policy as arrows.

        ``greedy`` defaults to argmax Q (first of ties); ``value_range`` fixes the
        colour scale (default: min..max over the free cells of each frame). The share of
        optimal greedy moves counts every reachable cell; the arrows are drawn on every
        ``k``-th cell (:func:`policy_arrow_cells`). Sent with the next flush.
        """
        m = self.model
        q = np.asarray(q, dtype=np.float64)
        greedy = np.argmax(q, axis=1) if greedy is None else np.asarray(greedy, np.int64)
        s = self._reachable
        g = greedy[s]
        ok = m.distance_to_goal[m.next_state[s, g]] == m.distance_to_goal[s] - 1
        a = self._arrows
        d = self._deltas[greedy[a]]
        ok_a = m.distance_to_goal[m.next_state[a, greedy[a]]] == m.distance_to_goal[a] - 1
        k = self._arrow_stride
        self._values.append(ValueFrame(
            episode=int(episode), step=max(self._step - 1, 0),
            v_nn=None if v_nn is None else self._heat(v_nn, value_range),
            max_q=self._heat(q.max(axis=1), value_range),
            # k cells long on a lattice of every k-th cell: a field of arrows readable at
            # a few pixels a cell (one per cell, each a cell long, was a grey texture)
            origins=(m.coords[a] - 0.4 * k * d).astype(np.float32),
            vectors=(0.8 * k * d).astype(np.float32), optimal=ok_a))
        self._add_scalars("policy_optimal", np.array([episode], np.int64),
                          np.array([float(ok.mean()) if len(s) else 0.0]))
        self._rows += m.n_states // 10
        self._maybe_flush()

    def log_route(self, name: str, states: Sequence[int] | np.ndarray,
                  episode: int | None = None, *, label: str | None = None,
                  path_m: np.ndarray | None = None) -> None:
        """A route as a labelled line (static, or at ``episode``). ``path_m`` (k, 2) [m]:
        draw the continuous drive (every physics step) instead of the cell centres;
        ``label``: the text shown (default: the route's moves, or "no G")."""
        pts = scene.route_points(self.model, states)
        colour = scene.ROUTE_PALETTE[self._n_routes % len(scene.ROUTE_PALETTE)]
        self._n_routes += 1
        states = np.asarray(states)
        reached = len(states) > 0 and int(states[-1]) == self.model.goal
        if label is None:
            label = (f"{name}: {len(pts) - 1} moves" if reached
                     else f"{name}: no G (loops at {len(pts) - 1})")
        if path_m is not None and len(path_m) > 1:
            pts = np.asarray(path_m, dtype=np.float64)[:, :2]
        sc = self.scenario
        strip = rr.LineStrips2D([pts], radii=0.1 * sc.cell_size_m, colors=[colour],
                                labels=[label], show_labels=False,
                                draw_order=scene.Z_ROUTE + 1)
        # the text under the arena, in the line's colour: never on an obstacle, S or G
        anchor = scene.route_label_anchor(self.model.bounds_m, self._n_routes - 1)
        text = rr.Points2D([anchor], radii=0.0, colors=[colour], labels=[label],
                           show_labels=True, draw_order=100.0)
        ent = self._p(f"world/routes/{rr.escape_entity_path_part(name)}")
        if episode is None:
            self.stream.log(ent, strip, static=True)
            self.stream.log(f"{ent}/label", text, static=True)
            return
        self.stream.set_time("episode", sequence=int(episode))
        try:
            self.stream.log(ent, strip)
            self.stream.log(f"{ent}/label", text)
        finally:
            self.stream.disable_timeline("episode")

    # ---------------------------------------------------------------- closing
    def close(self) -> None:
        """Flush; close the file if this recorder opened it. Safe to call twice."""
        if self.closed:
            return
        self.closed = True
        try:
            self.flush()
        finally:
            if self._pool is not None:
                self._pool.shutdown(wait=True)
            if self.owns_file:
                self.file.close()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
