"""The method registry and configs: paper defaults, validation, packing, round trips."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from learning import METHODS, RNHQL, STQL, config_from_fields
from learning.methods.registry import FAMILY_OF_CONFIG, comparison_methods

# the paper's method and its baselines, in the paper's order: they lead every table
PAPER = ("rnh-ql", "rnh-ql+", "st-ql", "rn-ql", "pfh-rl", "sarsa-rs", "haql")


def test_registry_names():
    """Read from the registry, not listed again here: a new method is one row there."""
    names = list(METHODS)
    assert names[:len(PAPER)] == list(PAPER) and len(set(names)) == len(names)
    compared = comparison_methods()
    # rnhql compare's default list is the registry's compared rows, in display order, and
    # every method run on request is listed after them
    assert compared == tuple(names[:len(compared)]) and set(PAPER) <= set(compared)
    assert METHODS["rnh-ql"].name == "RNH-QL" and METHODS["st-ql"].name == "ST-QL"
    for cli, cls in METHODS.items():
        assert cls.cli == cli and cls in FAMILY_OF_CONFIG


@pytest.mark.parametrize("cls", list(METHODS.values()), ids=list(METHODS))
def test_paper_defaults_and_round_trip(cls):
    cfg = cls()
    # the reference planners act on their own route (no epsilon); the learners as the paper
    assert (cfg.eps, cfg.alpha, cfg.gamma) == (0.0 if "alpha" in cls.IGNORED else 0.1, 0.1,
                                               0.95)
    if hasattr(cfg, "lam"):
        assert cfg.lam == 0.85
    assert config_from_fields(cls.cli, cfg.fields()) == cfg
    p = cfg.params()  # a named tuple of scalars, what the compiled rules read
    assert p.eps == cfg.eps and p.gamma == 0.95
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.eps = 0.2


def test_rnh_ql_defaults_and_packing():
    cfg = RNHQL()
    assert (cfg.k, cfg.warmup_episodes, cfg.freeze_after_episodes) == (10, 300, None)
    p = cfg.params()
    assert p.warmup == 300 and math.isinf(p.freeze)
    assert RNHQL(freeze_after_episodes=500).params().freeze == 500


@pytest.mark.parametrize("bad", [dict(eps=1.5), dict(alpha=0.0), dict(gamma=1.2)])
def test_invalid_common_fields(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        STQL(**bad)


@pytest.mark.parametrize("bad", [dict(lam=-0.1), dict(k=0), dict(beta=0.0),
                                 dict(warmup_episodes=-1), dict(freeze_after_episodes=-5)])
def test_invalid_rnh_ql_fields(bad):
    with pytest.raises(ValueError, match=f"RNHQL.{next(iter(bad))}"):
        RNHQL(**bad)


def test_unknown_method():
    with pytest.raises(ValueError, match="unknown method 'nope'"):
        config_from_fields("nope", {})


def test_rnh_ql_plus_defaults_packing_and_validation():
    from learning.methods.rnh_ql_plus import Params, RNHQLPlus

    cfg = RNHQLPlus()
    assert cfg.cli == "rnh-ql+"
    p = cfg.params()
    assert type(p) is Params and p.n_planning == cfg.n_planning == 10
    assert p.scale == cfg.shaping_scale and p.warmup == 0.0
    assert p.lookahead is True and p.known_route is True and p.sweeping is False
    assert config_from_fields("rnh-ql+", cfg.fields()) == cfg
    for bad in (dict(lookahead=2), dict(n_planning=-1), dict(shaping_scale=-1.0)):
        with pytest.raises(ValueError, match=f"RNHQLPlus.{next(iter(bad))}"):
            RNHQLPlus(**bad)


def test_rnh_ql_plus_ablation_defaults_packing_and_validation():
    from learning.methods.rnh_ql_plus_ablation import Params, Potential, RNHQLPlusAblation

    cfg = RNHQLPlusAblation()
    assert cfg.cli == "rnh-ql+ablation"
    p = cfg.params()
    assert type(p) is Params and p.n_planning == cfg.n_planning
    assert math.isinf(p.freeze) and p.rebase is False and p.lookahead is True
    assert p.v_target == Potential.OPTIMISTIC and p.n_fit == cfg.n_fit
    assert config_from_fields("rnh-ql+ablation", cfg.fields()) == cfg
    for bad in (dict(v_target=6), dict(lookahead=2), dict(leak_free=2), dict(sigma=0.0),
                dict(lam_q=1.5)):
        with pytest.raises(ValueError, match=f"RNHQLPlusAblation.{next(iter(bad))}"):
            RNHQLPlusAblation(**bad)


def test_haql_route_follows_what_it_learned_about_the_walls():
    """HAQL's heuristic from exploration: before training its greedy route runs into the
    first wall of zigzag-50 (G not reached); after training it is the optimal 212-move
    route. The static Manhattan heuristic never changes, so its route never reaches G."""
    from learning import HAQL
    from learning.drivers.state import init_state
    from learning.drivers.train import greedy_test, train_tabular
    from learning.geometry import geometry_of
    from learning.streams import streams
    from scenarios.runs.spec import load

    _, model = load("zigzag-50", None, None, "goal-only")
    fresh = init_state(HAQL(), geometry_of(model), np.random.default_rng(0))
    assert greedy_test(fresh, model)[0] == -1
    rs = streams(0)
    learned = train_tabular(HAQL(), model, 300, rs.learner, start_rng=rs.starts)
    assert learned.final_route_length == model.optimal_route_length == 212
    assert learned.state.free.blocked.any()  # it has seen walls
    rs = streams(0)
    static = train_tabular(HAQL(explored=0), model, 300, rs.learner, start_rng=rs.starts)
    assert static.final_route_length == -1
    untrained_static = init_state(HAQL(explored=0), geometry_of(model), np.random.default_rng(0))
    np.testing.assert_array_equal(static.state.pi_h, untrained_static.pi_h)
