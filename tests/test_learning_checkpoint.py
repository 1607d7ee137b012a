"""Checkpoints: exact resume, atomic writes, and errors that name the file, field and fix."""

from __future__ import annotations

import numpy as np
import pytest

from learning import (
    METHODS,
    RNHQL,
    STQL,
    Checkpoint,
    CheckpointError,
    load_checkpoint,
    make_agent,
    save_checkpoint,
    train_tabular,
)
from learning.compiled.named_state import arrays
from learning.drivers.train import EPISODE_FIELDS
from learning.geometry import geometry_of
from learning.methods.registry import family_of
from sim.grid import build_model
from sim.scenario_io import resolve_scenario

RESUME_CONFIGS = [c() for c in METHODS.values()] + [RNHQL(warmup_episodes=25)]


def assert_same_state(a, b, derived=()):
    """Every named array of two learner states equal (and the parameters), but the
    ``derived`` ones: a method's scratch that a load rebuilds (a search's marks and queue)
    need not hold what the uninterrupted run left there, so long as the run goes on alike
    (its episodes and tests are compared too)."""
    assert a.par == b.par
    left, right = dict(arrays(a)), dict(arrays(b))
    assert left.keys() == right.keys()
    for name, x in left.items():
        assert name in derived or np.array_equal(x, right[name]), name


@pytest.mark.parametrize("cfg", RESUME_CONFIGS, ids=lambda c: c.cli)
def test_resume_equals_uninterrupted(tmp_path, paper50_model, cfg):
    m = paper50_model
    full = train_tabular(cfg, m, 50, np.random.default_rng(11), test_every=10)
    rng = np.random.default_rng(11)
    half = train_tabular(cfg, m, 30, rng, test_every=10)
    path = save_checkpoint(tmp_path / "run.npz", Checkpoint.of_result(half, rng))
    ckpt = load_checkpoint(path, method=cfg.cli, n_states=m.n_states, geometry=geometry_of(m))
    assert ckpt.episodes == 30
    rest = train_tabular(cfg, m, 50, np.random.default_rng(999), test_every=10, resume=ckpt)
    assert_same_state(full.state, rest.state, getattr(family_of(cfg), "DERIVED", ()))
    for f in EPISODE_FIELDS:
        if f != "wall_time_s":
            np.testing.assert_array_equal(getattr(full, f), getattr(rest, f), err_msg=f)
    np.testing.assert_array_equal(full.test_route_length, rest.test_route_length)
    assert full.env_steps == rest.env_steps and full.final_route == rest.final_route


def test_agent_round_trip(tmp_path, paper50_model):
    geom = geometry_of(paper50_model)
    agent = make_agent(RNHQL(), geom, np.random.default_rng(0))
    agent.state.q[3, 2] = 7.0
    path = save_checkpoint(tmp_path / "a.npz", Checkpoint.of_agent(agent))
    ck = load_checkpoint(path, geometry=geom)
    assert ck.config == RNHQL() and ck.method == "rnh-ql" and ck.state.q[3, 2] == 7.0
    assert ck.rng_state == agent.rng.bit_generator.state


def test_write_is_atomic(tmp_path, paper50_model):
    agent = make_agent(STQL(), geometry_of(paper50_model), np.random.default_rng(0))
    path = tmp_path / "c.npz"
    save_checkpoint(path, Checkpoint.of_agent(agent))
    agent.state.q[0, 0] = 1.0
    save_checkpoint(path, Checkpoint.of_agent(agent))
    assert [p.name for p in tmp_path.iterdir()] == ["c.npz"]
    assert load_checkpoint(path).state.q[0, 0] == 1.0


@pytest.fixture
def saved(tmp_path, paper50_model):
    agent = make_agent(RNHQL(), geometry_of(paper50_model), np.random.default_rng(0))
    return save_checkpoint(tmp_path / "r.npz", Checkpoint.of_agent(agent))


def test_corrupt_file(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip at all")
    with pytest.raises(CheckpointError, match=r"bad\.npz.*not an rnhql checkpoint"):
        load_checkpoint(bad)


def test_a_foreign_npz_with_pickled_data_never_suggests_loading_it_unsafely(tmp_path):
    foreign = tmp_path / "foreign.npz"
    np.savez(foreign, format=np.array({"a": 1}, dtype=object), method=np.array("rnh-ql"))
    with pytest.raises(CheckpointError) as info:
        load_checkpoint(foreign)
    msg = str(info.value).replace(str(foreign), "FILE")
    assert msg.startswith("FILE:") and "not an rnhql checkpoint" in msg
    assert "unsafe" not in msg and "pickle" not in msg


def test_truncated_file(tmp_path, saved):
    cut = tmp_path / "cut.npz"
    cut.write_bytes(saved.read_bytes()[:2000])
    with pytest.raises(CheckpointError, match=r"cut\.npz"):
        load_checkpoint(cut)


def test_missing_field(tmp_path, saved):
    with np.load(saved) as d:
        payload = {k: d[k] for k in d.files if k != "state_q"}
    p = tmp_path / "partial.npz"
    np.savez(p, **payload)
    with pytest.raises(CheckpointError, match=r"partial\.npz: field 'state_q' is missing"):
        load_checkpoint(p)


def test_wrong_dtype(tmp_path, saved):
    with np.load(saved) as d:
        payload = {k: d[k] for k in d.files}
    payload["state_q"] = payload["state_q"].astype(np.float32)
    p = tmp_path / "dtype.npz"
    np.savez(p, **payload)
    with pytest.raises(CheckpointError, match="field 'state_q' is float32"):
        load_checkpoint(p)


def test_missing_file(tmp_path):
    with pytest.raises(CheckpointError, match="no such checkpoint"):
        load_checkpoint(tmp_path / "nope.npz")


def test_wrong_method(saved, paper50_model):
    with pytest.raises(CheckpointError, match=r"r\.npz: field 'method' is 'rnh-ql'.*--method"):
        load_checkpoint(saved, method="st-ql")
    ck = load_checkpoint(saved, geometry=geometry_of(paper50_model))
    with pytest.raises(CheckpointError, match="field 'method'"):
        train_tabular(STQL(), paper50_model, 10, np.random.default_rng(0), resume=ck)


def test_wrong_config(saved, paper50_model):
    ck = load_checkpoint(saved, geometry=geometry_of(paper50_model))
    with pytest.raises(CheckpointError, match="field 'config' differs in alpha"):
        train_tabular(RNHQL(alpha=0.2), paper50_model, 10, np.random.default_rng(0), resume=ck)


def test_wrong_state_count(saved, paper50_model):
    with pytest.raises(CheckpointError, match="field 'n_states' is 2500 but the scenario has 1600"):
        load_checkpoint(saved, n_states=1600)
    small = build_model(resolve_scenario("paper-40"))
    with pytest.raises(CheckpointError, match="n_states"):
        train_tabular(RNHQL(), small, 10, np.random.default_rng(0),
                      resume=load_checkpoint(saved, geometry=geometry_of(paper50_model)))


@pytest.mark.parametrize("q", [np.zeros((10, 4)), np.zeros((2500, 1)),
                               np.full((2500, 4), np.nan)])
def test_wrong_q_shape_or_nan_is_refused_before_compiled_code_sees_it(tmp_path, saved,
                                                                     paper50_model, q):
    with np.load(saved) as d:
        payload = {k: d[k] for k in d.files}
    payload["state_q"] = q
    p = tmp_path / "q.npz"
    np.savez(p, **payload)
    geom = geometry_of(paper50_model)
    # a table of 10 rows is read as a checkpoint of another scenario (10 states)
    with pytest.raises(CheckpointError, match=r"q\.npz: field ('state_q' (has shape|holds NaN)|"
                                              r"'n_states' is 10 but)"):
        load_checkpoint(p, n_states=2500, geometry=geom)
    with pytest.raises(CheckpointError, match="field 'state_q'"):
        train_tabular(RNHQL(), paper50_model, 10, np.random.default_rng(0),
                      resume=load_checkpoint(p, geometry=geom))
    load_checkpoint(saved, n_states=2500, geometry=geom)  # the intact file passes


def test_checkpoint_error_is_value_error():
    assert issubclass(CheckpointError, ValueError)


def test_env_agent_checkpoint_resumes_in_the_kernel(tmp_path, paper50_model):
    """20 episodes through gymnasium, saved, then 20 more in the kernel == 40 in the kernel."""
    import gymnasium as gym

    import sim.envs  # noqa: F401
    from learning import RNHQL, run_env_episodes

    cfg = RNHQL(warmup_episodes=10)
    env = gym.make("rnhql/GridRoute-v0", rewards="scenario")  # paper50_model's scheme
    agent = make_agent(cfg, geometry_of(env.unwrapped.model), np.random.default_rng(5))
    run_env_episodes(agent, env, 20)
    ck = load_checkpoint(save_checkpoint(tmp_path / "env.npz", Checkpoint.of_agent(agent)),
                         geometry=geometry_of(paper50_model))
    q_saved = ck.state.q.copy()
    rest = train_tabular(cfg, paper50_model, 40, np.random.default_rng(0), resume=ck)
    full = train_tabular(cfg, paper50_model, 40, np.random.default_rng(5))
    assert_same_state(full.state, rest.state)
    np.testing.assert_array_equal(full.steps[20:], rest.steps[20:])
    assert np.array_equal(ck.state.q, q_saved)  # resuming does not mutate the checkpoint


def test_more_episodes_than_asked(saved, paper50_model):
    ck = load_checkpoint(saved, geometry=geometry_of(paper50_model))
    ck.state.tally.episode[0] = 50
    with pytest.raises(CheckpointError, match="field 'episodes' is 50"):
        train_tabular(RNHQL(), paper50_model, 10, np.random.default_rng(0), resume=ck)


def test_rnh_ql_plus_ablation_keeps_no_rbf_features_it_never_reads_and_loads_older_ones(
        tmp_path, paper50_model):
    from learning import RNHQLPlusAblation
    from learning.methods.rnh_ql_plus_ablation.features import new_features

    geom = geometry_of(paper50_model)
    agent = make_agent(RNHQLPlusAblation(), geom, np.random.default_rng(0))
    assert agent.state.feat.on.size == 0 and agent.state.w.size == 0  # no network: no features
    with_net = make_agent(RNHQLPlusAblation(v_target=3), geom, np.random.default_rng(0))
    assert with_net.state.feat.on.shape[0] == geom.n_states and with_net.state.w.size > 0
    # a checkpoint of the default configuration written before: its unused features stored full
    old_feat = new_features(RNHQLPlusAblation(v_target=3), geom)
    agent.state = agent.state._replace(feat=old_feat, w=np.zeros(old_feat.anchor.shape[0]),
                                       v_trace=np.zeros(old_feat.anchor.shape[0]))
    agent.state.q[5, 1] = 3.0
    path = save_checkpoint(tmp_path / "old.npz", Checkpoint.of_agent(agent))
    ck = load_checkpoint(path, method="rnh-ql+ablation", geometry=geom)
    assert ck.state.q[5, 1] == 3.0 and ck.state.feat.on.size == 0 and ck.state.w.size == 0


def _as_written_before_the_split(path, **config):
    """Rewrite a checkpoint of rnh-ql+ablation as rnh-ql+'s checkpoints were written before
    the ablation's switches left rnh-ql+: the same state arrays (the ablation's state is
    rnh-ql+'s of then) and config fields, under the method name rnh-ql+."""
    import json

    with np.load(path) as data:
        fields = {k: data[k] for k in data.files}
    fields["method"] = np.array("rnh-ql+")
    fields["config"] = np.array(json.dumps({**json.loads(str(fields["config"])), **config}))
    np.savez(path, **fields)


def test_rnh_ql_plus_loads_its_checkpoints_from_before_the_ablation_split(tmp_path,
                                                                           paper50_model):
    """Such a checkpoint lists the ablation's switches in its config, at their defaults, and
    holds their arrays: it loads as rnh-ql+ (the switches and arrays dropped) and resumes
    as if never stopped; a switch at another value names the method that has it now."""
    from learning import RNHQLPlus, RNHQLPlusAblation

    geom = geometry_of(paper50_model)
    rng = np.random.default_rng(4)
    half = train_tabular(RNHQLPlusAblation(), paper50_model, 20, rng)
    path = save_checkpoint(tmp_path / "old.npz", Checkpoint.of_result(half, rng))
    _as_written_before_the_split(path)
    ck = load_checkpoint(path, method="rnh-ql+", n_states=geom.n_states, geometry=geom)
    assert ck.config == RNHQLPlus() and "w" not in ck.state._fields
    rest = train_tabular(RNHQLPlus(), paper50_model, 40, np.random.default_rng(0), resume=ck)
    full = train_tabular(RNHQLPlus(), paper50_model, 40, np.random.default_rng(4))
    assert_same_state(full.state, rest.state)
    np.testing.assert_array_equal(full.steps[20:], rest.steps[20:])
    _as_written_before_the_split(path, v_target=1)
    with pytest.raises(CheckpointError, match=r"field 'config': v_target = 1 .*rnh-ql\+ablation"):
        load_checkpoint(path, method="rnh-ql+", geometry=geom)


@pytest.mark.parametrize("method", ["rnh-ql+", "haql", "dyna-q", "rnh-ql+ablation"])
def test_a_checkpoint_from_before_a_methods_added_fields_loads_them_fresh(
        tmp_path, paper50_model, method):
    """A field a method gained later (its ``ADDED``, here the bump reading) is absent from
    older files: they load with a fresh agent's value, and every other field as stored."""
    from learning.methods.registry import family_of

    m = paper50_model
    cfg = METHODS[method]()
    added = family_of(cfg).ADDED
    derived = set(getattr(family_of(cfg), "DERIVED", ()))
    r = train_tabular(cfg, m, 5, np.random.default_rng(0))
    path = save_checkpoint(tmp_path / "new.npz", Checkpoint.of_result(r, np.random.default_rng(1)))
    with np.load(path) as d:
        payload = {k: d[k] for k in d.files if k.removeprefix("state_") not in added}
    assert len(payload) < len(np.load(path).files)
    old = tmp_path / "old.npz"
    np.savez(old, **payload)
    ck = load_checkpoint(old, geometry=geometry_of(m))
    fresh = dict(arrays(make_agent(cfg, geometry_of(m), np.random.default_rng(0)).state))
    got, want = dict(arrays(ck.state)), dict(arrays(r.state))
    for name in set(got) - derived:
        expect = fresh[name] if name in added else want[name]
        assert np.array_equal(got[name], expect), name
