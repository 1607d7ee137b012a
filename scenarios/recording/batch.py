"""Turning buffered episodes into Rerun columns, many episodes per ``send_columns`` call.

:meth:`scenarios.recording.Recorder.log_episode_trajectory` only copies its
arrays into an :class:`EpisodeRecord`; :func:`send_episodes` does the work for
a whole buffer at once (vectorised over all rows), which keeps the per-episode
cost of recording to a few microseconds plus the per-row cost of Rerun itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import rerun as rr

from scenarios.recording import scene
from sim.grid import TabularModel

MAX_CONTACT_EVENTS = 10  # contact events (text log rows) per episode; the rest are counted


@dataclass(frozen=True)
class EpisodeRecord:
    episode: int
    kind: str  # "train" | "greedy-test" | ...
    states: np.ndarray  # int64[n]; states[0] the start
    poses: np.ndarray | None  # float64[n, 3] (x, y, heading) or None: from the grid
    contacts: np.ndarray | None  # float64[k, 2] or None: grid bumps (grid world)
    contact_steps: np.ndarray | None  # int64[k] step of each contact within the episode
    sim_time: np.ndarray | None  # float64[n] [s] or None
    step0: int  # value of the `step` timeline at states[0]
    sim0: float  # value of `sim_time` at states[0] [s]
    substeps: tuple[np.ndarray, np.ndarray] | None = None  # physics: (poses [m, m, rad],
    #                                                      `sim_time` values [s]) of every step


@dataclass(frozen=True)
class ValueFrame:
    episode: int
    step: int  # `step` timeline value: the last recorded row so far
    v_nn: tuple[np.ndarray, float, float] | None  # (float32[ny, nx], lo, hi)
    max_q: tuple[np.ndarray, float, float]
    origins: np.ndarray  # float32[k, 2] policy arrows over the reachable cells
    vectors: np.ndarray  # float32[k, 2]
    optimal: np.ndarray  # bool[k]: the greedy move is a shortest-route move


def grid_poses(model: TabularModel, states: np.ndarray,
               starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres and heading vectors (one cell long) per episode, rows from ``starts``.

    The heading is the direction of the last move; before an episode's first
    move the robot faces the way that move goes, without moves it faces +x.
    """
    n = len(states)
    xy = model.coords[states]
    moved = np.zeros(n, dtype=bool)
    moved[1:] = states[1:] != states[:-1]
    moved[starts] = False
    d = np.zeros((n, 2))
    d[1:] = xy[1:] - xy[:-1]
    mv = np.flatnonzero(moved)
    ends = np.append(starts[1:], n)
    d[starts] = (model.cell_size_m, 0.0)
    if len(mv):
        j = np.minimum(np.searchsorted(mv, starts), len(mv) - 1)
        has = (mv[j] >= starts) & (mv[j] < ends)
        d[starts[has]] = d[mv[j[has]]]
    mark = moved.copy()
    mark[starts] = True
    return xy, d[np.maximum.accumulate(np.where(mark, np.arange(n), 0))]


def _visited(model: TabularModel, states: np.ndarray, lens: np.ndarray) -> tuple[np.ndarray, ...]:
    """Distinct cells per episode: (centres, count per episode)."""
    e, ns = len(lens), model.n_states
    keys = np.repeat(np.arange(e, dtype=np.int64) * ns, lens) + states
    if e * ns <= 50_000_000:  # a flat mark and one scan: ~4x faster than a 2-D nonzero
        mark = np.zeros(e * ns, dtype=bool)
        mark[keys] = True
        keys = np.flatnonzero(mark)
    else:
        keys = np.unique(keys)
    rows = keys // ns
    return model.coords[keys - rows * ns], np.bincount(rows, minlength=e)


def _timecols(tl: dict[str, np.ndarray]) -> list[rr.TimeColumn]:
    """Index columns; ``sim_time`` [s] is rounded to whole nanoseconds (not truncated)."""
    return [rr.TimeColumn(k, duration=np.round(v * 1e9).astype("timedelta64[ns]"))
            if k == "sim_time" else rr.TimeColumn(k, sequence=v) for k, v in tl.items()]


def send_episodes(stream: rr.RecordingStream, prefix: str, model: TabularModel, world: str,
                  records: list[EpisodeRecord]) -> None:
    groups: dict[tuple[str, bool], list[EpisodeRecord]] = {}
    for r in records:
        groups.setdefault((r.kind, r.sim_time is not None), []).append(r)
    for (kind, _), rs in groups.items():
        _send_group(stream, prefix, model, world, kind, rs)


def _send_group(stream: rr.RecordingStream, prefix: str, model: TabularModel, world: str,
                kind: str, rs: list[EpisodeRecord]) -> None:
    p = scene.path
    lens = np.array([len(r.states) for r in rs])
    offs = np.concatenate([[0], np.cumsum(lens)])
    starts, n = offs[:-1], int(offs[-1])
    states = np.concatenate([r.states for r in rs])
    within = np.arange(n) - np.repeat(starts, lens)
    tl = {"step": np.repeat([r.step0 for r in rs], lens) + within,
          "episode": np.repeat(np.array([r.episode for r in rs], dtype=np.int64), lens)}
    if rs[0].sim_time is not None:
        tl["sim_time"] = np.concatenate([r.sim0 + (r.sim_time - r.sim_time[0]) for r in rs])
    c = model.cell_size_m
    if all(r.poses is None for r in rs):
        xy64, vec64 = grid_poses(model, states, starts)
    else:
        xy64, vec64 = np.empty((n, 2)), np.empty((n, 2))
        for r, o, ln in zip(rs, starts.tolist(), lens.tolist(), strict=True):
            if r.poses is None:
                xy64[o:o + ln], vec64[o:o + ln] = grid_poses(model, r.states, np.zeros(1, int))
            else:
                xy64[o:o + ln] = r.poses[:, :2]
                vec64[o:o + ln, 0] = c * np.cos(r.poses[:, 2])
                vec64[o:o + ln, 1] = c * np.sin(r.poses[:, 2])
    xy, vec = xy64.astype(np.float32), vec64.astype(np.float32)
    stream.send_columns(p(prefix, "world/robot"), indexes=_timecols(tl),
                        columns=[*rr.Points2D.columns(positions=xy),
                                 *rr.Arrows2D.columns(origins=xy, vectors=vec)])
    subs = [r.substeps for r in rs if r.substeps is not None]
    if subs:  # the continuous drive between the states, on `sim_time` only
        sp = np.concatenate([s[0] for s in subs])
        sxy = sp[:, :2].astype(np.float32)
        svec = (c * np.stack([np.cos(sp[:, 2]), np.sin(sp[:, 2])], axis=1)).astype(np.float32)
        stream.send_columns(p(prefix, "world/robot"),
                            indexes=_timecols({"sim_time": np.concatenate([s[1] for s in subs])}),
                            columns=[*rr.Points2D.columns(positions=sxy),
                                     *rr.Arrows2D.columns(origins=sxy, vectors=svec)])

    k = f"world/{scene.kind_part(kind)}"
    first = {name: v[starts] for name, v in tl.items()}
    stream.send_columns(p(prefix, f"{k}/trajectory"), indexes=_timecols(first),
                        columns=_strips(xy, offs))
    centres, counts = _visited(model, states, lens)
    stream.send_columns(p(prefix, f"{k}/visited"), indexes=_timecols(first),
                        columns=rr.Points2D.columns(positions=centres).partition(counts))

    # contacts: given, or the grid's bumps (a move that left the state unchanged)
    e = len(rs)
    bumps = all(r.contacts is None for r in rs)
    if bumps:
        rows = np.zeros(0, np.int64)
        if world == "grid":
            bump = np.zeros(n, dtype=bool)
            bump[1:] = states[1:] == states[:-1]
            bump[starts] = False
            rows = np.flatnonzero(bump)
        epi = np.searchsorted(starts, rows, side="right") - 1
        pts, cs = xy[rows], rows - starts[epi]
    else:
        parts = [(np.zeros((0, 2)) if r.contacts is None else r.contacts,
                  np.zeros(0 if r.contacts is None else len(r.contacts), np.int64)
                  if r.contact_steps is None else np.clip(r.contact_steps, 0, len(r.states) - 1))
                 for r in rs]
        epi = np.repeat(np.arange(e), [len(q[0]) for q in parts])
        pts = np.concatenate([q[0] for q in parts]).astype(np.float32).reshape(-1, 2)
        cs = np.concatenate([q[1] for q in parts]).astype(np.int64)
    counts = np.bincount(epi, minlength=e)
    stream.send_columns(p(prefix, f"{k}/contacts"), indexes=_timecols(first),
                        columns=rr.Points2D.columns(positions=pts).partition(counts))

    # events: one summary per episode, then the first given contacts of each (grid bumps
    # are only counted: they are many and all alike)
    rank = np.arange(len(epi)) - np.repeat(np.cumsum(counts) - counts, counts)
    sel = np.flatnonzero(rank < (0 if bumps else MAX_CONTACT_EVENTS))
    ok = model.terminal[states[offs[1:] - 1]].tolist()
    capped = f" (events for the first {MAX_CONTACT_EVENTS})" if not bumps else ""
    texts = [f"episode {r.episode} ({kind}): {ln - 1} moves, "
             f"{nc} {'bump' if bumps else 'contact'}{'' if nc == 1 else 's'}"
             f"{capped if nc > MAX_CONTACT_EVENTS else ''}, "
             f"{'reached the goal' if g else 'did not reach the goal'}"
             for r, ln, nc, g in zip(rs, lens.tolist(), counts.tolist(), ok, strict=True)]
    eps = [r.episode for r in rs]
    texts += [f"episode {eps[i]}: contact at ({x:.2f}, {y:.2f}) m, step {c}"
              for i, (x, y), c in zip(epi[sel].tolist(), pts[sel].astype(float).tolist(),
                                      cs[sel].tolist(), strict=True)]
    tr = np.concatenate([starts, starts[epi[sel]] + cs[sel]])
    levels = ["INFO"] * e + ["WARN"] * len(sel)
    stream.send_columns(p(prefix, f"{k}/events"), indexes=_timecols({nm: v[tr]
                                                                      for nm, v in tl.items()}),
                        columns=rr.TextLog.columns(text=texts, level=levels))


def _strips(xy: np.ndarray, offs: np.ndarray) -> rr.ComponentColumnList:
    """One line strip per episode, built as one Arrow array (not strip by strip)."""
    t = rr.components.LineStrip2DBatch._ARROW_DATATYPE
    try:
        values = pa.FixedSizeListArray.from_arrays(pa.array(xy.reshape(-1), pa.float32()),
                                                   type=t.value_type)
        arr = pa.ListArray.from_arrays(pa.array(offs.astype(np.int32)), values, type=t)
        return rr.LineStrips2D.columns(strips=arr)
    except (pa.ArrowException, TypeError, ValueError):  # a Rerun upgrade changed the type
        return rr.LineStrips2D.columns(strips=np.split(xy, offs[1:-1]))


def send_values(stream: rr.RecordingStream, prefix: str, model: TabularModel,
                frames: list[ValueFrame], potential: str = "V_NN") -> None:
    """Heat maps (DepthImage rows), their legends and the policy arrows of many frames;
    ``potential`` names the ``v_nn`` map in its legend (what the method shapes with)."""
    p = scene.path
    for name, label in (("v_nn", potential), ("max_q", "max_a Q")):
        fs = [f for f in frames if getattr(f, name) is not None]
        if not fs:
            continue
        heat = [getattr(f, name) for f in fs]
        tl = _timecols({"episode": np.array([f.episode for f in fs], np.int64),
                        "step": np.array([f.step for f in fs], np.int64)})
        fmt = rr.components.ImageFormat(width=model.nx, height=model.ny,
                                        channel_datatype="F32", color_model="L")
        ent = p(prefix, f"world/values/{name}")
        stream.send_columns(ent, indexes=tl, columns=rr.DepthImage.columns(
            buffer=[h[0].tobytes() for h in heat], format=[fmt] * len(fs),
            depth_range=[[h[1], h[2]] for h in heat]))
        stream.send_columns(f"{ent}/legend", indexes=tl, columns=rr.Points2D.columns(
            labels=[f"{label}: {h[1]:.3g} (dark) … {h[2]:.3g} (yellow)" for h in heat]))
    tl = _timecols({"episode": np.array([f.episode for f in frames], np.int64),
                    "step": np.array([f.step for f in frames], np.int64)})
    ok = np.concatenate([f.optimal for f in frames])
    colours = np.where(ok[:, None], scene.POLICY_OK, scene.POLICY_BAD).astype(np.uint8)
    stream.send_columns(p(prefix, "world/values/policy"), indexes=tl, columns=rr.Arrows2D.columns(
        origins=np.concatenate([f.origins for f in frames]),
        vectors=np.concatenate([f.vectors for f in frames]), colors=colours,
    ).partition([len(f.optimal) for f in frames]))
