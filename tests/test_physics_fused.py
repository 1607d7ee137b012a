"""The fused physics step (:mod:`scenarios.runs.physics_fused`) trains the runs the lock-step
loop trains: per-episode logs, greedy tests, learned state and final grade, bit for bit, at
``exact`` and on rungs that draw noise (refilled in compiled code), carry the pose, drift
open loop, localise or lag; and next to runs it cannot drive (plain-Python learners)."""

from __future__ import annotations

import numpy as np
import pytest

from learning.plain.learner import plain_config
from learning.streams import streams
from scenarios.runs.physics import RunGroup, train_physics_runs
from scenarios.runs.spec import load, make_config
from sim.physics.fidelity import parse_fidelity

LOGS = ("steps", "returns", "success", "shaping_mean", "shaping_std", "test_episodes",
        "test_route_length")
EXTRAS = ("contacts_per_episode", "sim_time_per_episode_s")


def _groups(methods, seeds=2):
    out = []
    for m in methods:
        rs = [streams(s) for s in range(seeds)]
        cfg = make_config(m) if isinstance(m, str) else m
        out.append(RunGroup(cfg, [r.learner for r in rs], [r.starts for r in rs],
                            [r.physics for r in rs]))
    return out


class GreedyCounts:
    """A plain-Python learner: Q-learning, ties broken by its stream."""

    def __init__(self, n_states, n_actions, rng):
        self.q, self.rng = np.zeros((n_states, n_actions)), rng

    def act(self, s):
        return int(self.rng.integers(4)) if self.rng.random() < 0.1 else self.greedy(s)

    def update(self, s, a, r, s2, terminal):
        self.q[s, a] += 0.1 * (r + (0.0 if terminal else 0.95 * self.q[s2].max())
                               - self.q[s, a])

    def greedy(self, s):
        return int(np.argmax(self.q[s]))


def _arrays(st, path=""):
    """Every array of a (nested) learner state, by path."""
    for name in getattr(st, "_fields", ()):
        v = getattr(st, name)
        if isinstance(v, np.ndarray):
            yield f"{path}{name}", v
        elif hasattr(v, "_fields"):
            yield from _arrays(v, f"{path}{name}.")


def _differences(a, b):
    diffs = []
    for ga, gb in zip(a, b, strict=True):
        for ra, rb in zip(ga, gb, strict=True):
            name = ra.config.name
            diffs += [f"{name} {f}" for f in LOGS
                      if not np.array_equal(getattr(ra, f), getattr(rb, f))]
            diffs += [f"{name} {f}" for f in EXTRAS if ra.world_extras[f] != rb.world_extras[f]]
            diffs += [f"{name} state.{p}" for (p, x), (_, y) in
                      zip(_arrays(ra.state), _arrays(rb.state), strict=True)
                      if not np.array_equal(x, y, equal_nan=True)]
            if (ra.final_route_length, ra.final_route) != (rb.final_route_length,
                                                           rb.final_route):
                diffs.append(f"{name} final route")
    return diffs


@pytest.mark.parametrize(("scenario", "fidelity", "methods"), [
    ("paper-40", "exact", ("st-ql", "rnh-ql", "sarsa-rs")),
    ("maze-1", "noisy", ("st-ql", "dyna-q")),
    ("maze-1", "open-loop", ("q-lambda",)),
    ("paper-40", "localised", ("st-ql",)),
    ("maze-1", "latency", ("st-ql",)),
])
def test_fused_runs_are_the_lock_step_runs(scenario, fidelity, methods):
    sc, model = load(scenario, None, None, "goal-only")
    fid = parse_fidelity(fidelity)
    runs = [train_physics_runs(sc, model, _groups(methods), 20, 10, fidelity=fid, fused=f)
            for f in (False, True)]
    assert _differences(*runs) == []
    assert sum(int(r.steps.sum()) for g in runs[1] for r in g) > 0


def test_fused_and_plain_learners_share_a_loop():
    """A plain-Python learner's group steps in lock-step after the compiled groups are done;
    every run is the run it is alone."""
    sc, model = load("paper-40", None, None, "goal-only")
    plain = plain_config(GreedyCounts, "tests.test_physics_fused:GreedyCounts")()
    mixed = train_physics_runs(sc, model, _groups(("st-ql",)) + _groups((plain,), seeds=1),
                               10, 5)
    alone = [train_physics_runs(sc, model, g, 10, 5, fused=False)[0]
             for g in (_groups(("st-ql",)), _groups((plain,), seeds=1))]
    assert _differences(mixed, alone) == []


def test_split_names_the_fused_time():
    sc, model = load("paper-40", None, None, "goal-only")
    split: dict[str, float] = {}
    train_physics_runs(sc, model, _groups(("st-ql",)), 5, 5, split=split)
    assert split["fused"] > 0.0 and split["kernel"] == 0.0
    assert split["primitives"] > 0


@pytest.mark.parametrize("fidelity", ["exact", "noisy", "localised", "slip"])
def test_compiled_drives_are_the_stepped_drives(fidelity):
    """Table policies drive whole in compiled code (sim.physics.kernel.rollout), shown drives
    step through the env; every figure equals the env's drive of the same policy as a
    callable (which always steps)."""
    from sim.physics.models.rollouts import drive_policies, drive_policy
    from sim.physics.models.solve import shortest_route_policy

    sc, model = load("paper-40", None, None, "goal-only")
    opt = shortest_route_policy(model)
    rng = np.random.default_rng(2)
    tables = [opt] + [np.where(rng.random(opt.size) < 0.05, rng.integers(0, 4, opt.size), opt)
                      for _ in range(2)]
    fid = parse_fidelity(fidelity)
    for kw in ({"keep_routes": True}, {"measure_metres": True, "keep_path": True}):
        fast = drive_policies(sc, tables, fid, 4, [3, 4, 5], [1, 2, 3], 120, **kw)
        for table, seed, tag, a in zip(tables, (3, 4, 5), (1, 2, 3), fast, strict=True):
            b = drive_policy(sc, lambda s, t=table: t[s], fid, 4, seed, tag, 120, **kw)
            for f in ("reached", "primitives", "contacts", "bumps", "sim_time_s", "metres",
                      "path", "poses"):
                np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
            assert a.routes == b.routes
        assert any(r.reached.any() for r in fast)


def test_the_fused_cache_goes_when_a_learner_or_the_kernel_changes(tmp_path, monkeypatch):
    """The fused call inlines learning's hooks and sim.physics' kernel: its numba cache is
    stamped with both packages' sources (a learner's module that moved left a cached call
    importing a module that was gone)."""
    from scenarios.runs import physics_fused

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    module = tmp_path / "physics_fused.py"
    module.write_text("# a stand-in\n")
    cached = tmp_path / "__pycache__" / "physics_fused.drive_runs-1.py311.nbi"
    cached.parent.mkdir()
    cached.write_text("")
    assert physics_fused.drop_stale_cache(module) and not cached.exists()
    cached.write_text("")
    assert not physics_fused.drop_stale_cache(module) and cached.exists()  # nothing changed
    monkeypatch.setattr(physics_fused, "learning_digest", lambda: "an edited learner")
    assert physics_fused.drop_stale_cache(module) and not cached.exists()
