"""rnh-ql+ and its ablation: the default method has none of the ablation's switches, and the
ablation at its defaults is rnh-ql+ run for run (the split kept the behaviour)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from learning import RNHQLPlus, RNHQLPlusAblation, train_tabular
from learning.compiled.named_state import arrays
from learning.methods.rnh_ql_plus.config import RETIRED

SWITCHES = ("v_target", "rebase", "leak_free", "lam_q", "spacing", "n_fit", "beta", "lam",
            "freeze_after_episodes", "normalise", "sigma", "cutoff", "k", "trace_min")


def test_rnh_ql_plus_has_none_of_the_ablations_switches():
    import learning.methods.rnh_ql_plus as plus
    from learning.methods.rnh_ql_plus import rules

    own = {f.name for f in dataclasses.fields(RNHQLPlus)}
    assert own.isdisjoint(SWITCHES) and set(RETIRED) == set(SWITCHES)
    assert set(RNHQLPlus().params()._fields).isdisjoint({"v_target", "rebase", "lam_q",
                                                          "leak_free", "freeze", "n_fit"})
    assert not {"w", "v_trace", "phi_row", "feat", "traces", "step_v",
                "train_v"} & set(plus.State._fields)
    for name in ("GENERAL", "lean_hooks", "rebase", "potential", "fit_v"):
        assert not hasattr(rules, name), name
    assert not hasattr(plus, "LEAN_PARAMS") and not hasattr(plus, "LEAN_HOOKS")


def test_the_ablations_defaults_are_rnh_ql_plus():
    """Its switches default to what rnh-ql+ is; a record of either lists the same config."""
    abl = RNHQLPlusAblation()
    assert {k: abl.fields()[k] for k in RETIRED} == RETIRED
    listed = {k: v for k, v in abl.fields().items() if k not in RNHQLPlus.UNLISTED_AT_DEFAULT}
    assert RNHQLPlus().record_fields() == abl.record_fields() == listed
    for k, v in RNHQLPlus().fields().items():
        assert getattr(abl, k) == v


@pytest.mark.parametrize("fields", [{}, dict(sweeping=1), dict(lookahead=0, n_planning=3),
                                    dict(known_route=0, warmup_episodes=7, shaping_scale=0.5)],
                         ids=["default", "sweeping", "no-lookahead", "warmup"])
def test_the_ablation_at_its_defaults_runs_as_rnh_ql_plus(paper50_model, fields):
    for seed in (0, 1):
        a = train_tabular(RNHQLPlus(**fields), paper50_model, 60, np.random.default_rng(seed),
                          test_every=10)
        b = train_tabular(RNHQLPlusAblation(**fields), paper50_model, 60,
                          np.random.default_rng(seed), test_every=10)
        np.testing.assert_array_equal(a.returns, b.returns)
        np.testing.assert_array_equal(a.steps, b.steps)
        np.testing.assert_array_equal(a.test_route_length, b.test_route_length)
        shared = dict(arrays(b.state))
        for name, x in arrays(a.state):  # every array rnh-ql+ has, the ablation has alike
            if name.startswith("coverage."):  # the coverage walk, rnh-ql+'s own option:
                continue  # untouched at explore_steps = 0 (test_learning_plus)
            assert np.array_equal(x, shared[name]), name
        assert (a.state.coverage.distance == -1).all() and a.state.coverage.left[0] == 0
        assert not a.state.coverage.done[0] and a.state.coverage.searches[0] == 0


def test_config_from_fields_drops_the_switches_at_rnh_ql_plus_values_only():
    from learning import config_from_fields
    from learning.config import FieldMovedError

    assert config_from_fields("rnh-ql+", {**RETIRED, "n_planning": 3}) == RNHQLPlus(n_planning=3)
    with pytest.raises(FieldMovedError, match=r"rebase = 1 .*method rnh-ql\+ablation"):
        config_from_fields("rnh-ql+", {**RETIRED, "rebase": 1})
    with pytest.raises(TypeError):  # a field no version of rnh-ql+ had stays an error
        config_from_fields("rnh-ql+", {"nope": 1})


def test_setting_a_switch_on_rnh_ql_plus_points_to_the_ablation():
    from scenarios.runs.spec import ExperimentError, make_config

    with pytest.raises(ExperimentError, match=r"method='rnh-ql\+ablation', which has v_target"):
        make_config("rnh-ql+", (("v_target", 1.0),))
    from scenarios.cli import main  # the command says it in its flags

    assert main(["train", "paper-40", "--set", "v_target=1", "--episodes", "2"]) == 2
    assert make_config("rnh-ql+ablation", (("v_target", 1.0),)).v_target == 1
