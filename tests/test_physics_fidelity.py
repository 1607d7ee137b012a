"""The fidelity ladder: presets and knobs, determinism per seed, carried pose that never
passes through what it touches, and batched noisy runs equal to single ones."""

from __future__ import annotations

import numpy as np
import pytest

from scenarios.runs.physics_batch import run_physics_batch
from scenarios.runs.run import run_one
from scenarios.runs.spec import RunSpec
from sim.errors import ScenarioError
from sim.grid import build_model
from sim.physics.fidelity import PRESETS, Fidelity, fidelity_from_table, parse_fidelity
from sim.physics.kernel.batch import RouteBatch
from sim.scenario_io import resolve_scenario


def test_presets_and_knobs():
    assert parse_fidelity(None) == Fidelity() == PRESETS["exact"]
    noisy = parse_fidelity("noisy")
    assert noisy.wheel_noise > 0 and noisy.carried_pose and noisy.label == "noisy"
    custom = parse_fidelity("noisy,wheel_noise=0.1")
    assert custom.wheel_noise == 0.1 and custom.carried_pose and "wheel_noise=0.1" in custom.label
    assert parse_fidelity("carried_pose=true").carried_pose
    assert fidelity_from_table({"fidelity": "noisy", "wheel_noise": 0.02}, "s.toml").wheel_noise \
        == 0.02
    for bad, words in (("bogus", "unknown preset"), ("wheel_noise=-1", "must be in"),
                       ("wheel_noise=abc", "expected a number"), ("colour=1", "not a fidelity"),
                       ("carried_pose=maybe", "true or false")):
        with pytest.raises(ScenarioError, match=words):
            parse_fidelity(bad)


def _walk(sc, fid, seeds, n_steps=250, actions_seed=0):
    model = build_model(sc)
    n = len(seeds)
    batch = RouteBatch(sc, n, fidelity=parse_fidelity(fid))
    for i, seed in enumerate(seeds):
        batch.set_noise_rng(i, np.random.default_rng(seed))
        x, y = batch.disc.state_centre(int(model.start_states[(37 * seed) % len(
            model.start_states)]))
        batch.place(i, x, y, 0.0)
    rng = np.random.default_rng(actions_seed)
    states, bumps, deepest = [], 0, 0.0
    for _ in range(n_steps):
        out = batch.step(rng.integers(0, 4, n))
        states.append(out.state.copy())
        bumps += int(out.bumped.sum())
        deepest = max(deepest, max(batch.overlap_m(i) for i in range(n)))
    return np.array(states), batch.poses(), bumps, deepest


def test_noisy_is_deterministic_per_seed_and_differs_from_exact():
    sc = resolve_scenario("paper-50")
    a = _walk(sc, "noisy", [1, 2, 3])
    b = _walk(sc, "noisy", [1, 2, 3])
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    c = _walk(sc, "noisy", [4, 5, 6])
    assert not np.array_equal(a[1], c[1])
    exact = _walk(sc, "exact", [1, 2, 3])
    assert not np.array_equal(a[1], exact[1])


def test_a_noisy_robot_in_a_batch_is_the_robot_alone():
    sc = resolve_scenario("paper-40")
    together = _walk(sc, "noisy", [7, 8], actions_seed=3)
    # the same robots alone need the same actions: replay robot 0's column
    model = build_model(sc)
    rng = np.random.default_rng(3)
    acts = rng.integers(0, 4, (250, 2))
    alone = RouteBatch(sc, 1, fidelity=parse_fidelity("noisy"))
    alone.set_noise_rng(0, np.random.default_rng(7))
    x, y = alone.disc.state_centre(int(model.start_states[(37 * 7) % len(model.start_states)]))
    alone.place(0, x, y, 0.0)
    states = [alone.step(acts[k, :1]).state[0] for k in range(250)]
    assert np.array_equal(np.array(states), together[0][:, 0])
    assert np.array_equal(alone.poses()[0], together[1][0])


def test_carried_pose_never_passes_through_what_it_touches():
    sc = resolve_scenario("arena")
    _, poses, bumps, deepest = _walk(sc, "noisy", [11, 12, 13, 14], n_steps=400)
    assert bumps > 20  # it did run into things, and stayed where it stopped
    assert deepest <= 0.005 + 1e-9  # never deeper than the contact depth
    assert ((poses[:, 0] > 0) & (poses[:, 0] < sc.width_m) & (poses[:, 1] > 0)
            & (poses[:, 1] < sc.height_m)).all()


@pytest.mark.parametrize("method", ["rnh-ql+", "dyna-q"])
def test_batched_noisy_runs_equal_single_runs(method):
    specs = [RunSpec("paper-40", method, seed, 15, world="physics", rewards="goal-only",
                     fidelity="noisy") for seed in (0, 1)]
    wall = ("wall_time_s", "wall_time_per_episode_s")
    for spec, rec in zip(specs, run_physics_batch(specs), strict=True):
        one = run_one(spec)
        assert rec["fidelity"] == "noisy" and "fid=noisy" in rec["key"]
        assert {k: v for k, v in rec.items() if k not in wall} == \
            {k: v for k, v in one.items() if k not in wall}


def test_a_scenario_physics_table_sets_the_fidelity(tmp_path):
    from scenarios.runs.spec import scenario_digest

    base = ('name = "t"\nstart = [1, 1]\ngoal = [8, 8]\n[arena]\nwidth_m = 10.0\n'
            'height_m = 10.0\n')
    plain, noisy, bad = tmp_path / "plain.toml", tmp_path / "noisy.toml", tmp_path / "bad.toml"
    plain.write_text(base)
    noisy.write_text(base + '[physics]\nfidelity = "noisy"\nwheel_noise = 0.02\n')
    bad.write_text(base + "[physics]\nwheel_noise = 7\n")
    sc = resolve_scenario(str(noisy))
    assert parse_fidelity(sc.physics).wheel_noise == 0.02
    assert RunSpec(str(noisy), "st-ql", 0, 5, world="physics").fidelity_spec.carried_pose
    assert RunSpec(str(plain), "st-ql", 0, 5, world="physics").fidelity_spec.is_exact
    assert RunSpec(str(noisy), "st-ql", 0, 5, world="physics",
                   fidelity="exact").fidelity_spec.is_exact  # --fidelity wins
    assert scenario_digest(str(plain)) != scenario_digest(str(noisy))
    with pytest.raises(ScenarioError, match=r"bad\.toml.*wheel_noise"):
        resolve_scenario(str(bad))


def test_every_knob_reaches_the_kernel_under_its_own_name():
    """Adding a knob is the dataclass field (with its check) in sim/physics/fidelity.py, its
    rule in the kernel (``p.<knob>``) and in the reference controller: the kernel's
    constants take every knob from the dataclass by name, with no list to extend."""
    import dataclasses

    from sim.physics.fidelity import PRESETS, Fidelity
    from sim.physics.kernel.state import FIDELITY_KNOBS, Params, params_of

    knobs = [f.name for f in dataclasses.fields(Fidelity) if f.name != "name"]
    assert list(FIDELITY_KNOBS) == knobs and set(knobs) <= set(Params._fields)
    derived = ("biased", "latency", "lag_keep", "delay", "slips", "slip_p")  # from the knobs
    drive = {f: 0.1 if f == "period" else 0 for f in Params._fields
             if f not in knobs and f not in derived}
    for fid in PRESETS.values():
        p = params_of(fid, **drive)
        assert all(getattr(p, k) == getattr(fid, k) for k in knobs), fid.name
        assert p.biased == fid.biased and p.latency == fid.latency and p.slips == fid.slips
