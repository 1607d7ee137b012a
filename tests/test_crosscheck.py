"""``rnhql crosscheck``: the same primitives and policies in IR-SIM, on a small map.

IR-SIM is an optional extra (``rnhql[crosscheck]``, in the test extra): its own Euler
kinematics, Shapely collisions and velocity noise. What is checked here: the noise
calibration against the per-wheel model it stands in for, the agreement on a small map at
``exact`` (every primitive) and ``noisy`` (the outcome distributions), and the command's
refusals.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from scenarios.cli import main
from sim.grid import build_model
from sim.physics.fidelity import parse_fidelity
from sim.physics.reference.controller import wheel_twist
from sim.scenario import Circle, Scenario

irsim = pytest.importorskip("irsim", reason="IR-SIM is the crosscheck extra")

from sim.physics.crosscheck.agreement import (  # noqa: E402 (after the skip)
    CrosscheckOptions,
    crosscheck,
    draw_pairs,
    grid_optimal_policy,
    strata,
)
from sim.physics.crosscheck.irsim_world import (  # noqa: E402
    SUBSTEPS,
    CrosscheckError,
    calibrated_alpha,
    check_rung,
)

SMALL = Scenario(name="small", width_m=8.0, height_m=8.0, start=(1, 1), goal=(6, 6),
                 obstacles=(Circle(3.3, 3.5, 0.7), Circle(5.6, 2.2, 0.45),
                            Circle(2.0, 6.0, 0.5)))


def test_the_noise_calibration_gives_the_per_wheel_models_period_variances():
    """IR-SIM draws (v, omega) noise per step; averaged over a period's SUBSTEPS steps its
    variances equal those of per-wheel noise on the period's command (Monte Carlo of
    :func:`wheel_twist`, the kernel's own rule)."""
    sigma, base = 0.05, SMALL.robot.wheel_base_m
    a0, a1, a2, a3 = calibrated_alpha(sigma, base)
    rng = np.random.default_rng(0)
    e = rng.standard_normal((200_000, 2))
    for v, w in ((0.5, 0.0), (0.0, 2.0), (0.3, 1.0)):
        got = np.array([wheel_twist(v, 0.0, w, 0.0, 0.0, 0.0, 0.0, el, er, sigma, base)
                        for el, er in e[:40_000]])
        var_v, var_w = got[:, 0].var(), got[:, 2].var()
        assert var_v == pytest.approx((a0 * v * v + a1 * w * w) / SUBSTEPS, rel=0.03)
        assert var_w == pytest.approx((a2 * v * v + a3 * w * w) / SUBSTEPS, rel=0.03)


def test_rungs_irsim_cannot_model_are_refused_naming_the_knob():
    for rung, knob in (("uncalibrated", "wheel_ratio_sigma"), ("open-loop", "open_loop"),
                       ("localised", "localisation"), ("latency", "lag_tau_s"),
                       ("slip", "slip_rate_hz")):
        with pytest.raises(CrosscheckError, match=knob):
            check_rung(parse_fidelity(rung))
    check_rung(parse_fidelity("noisy"))  # wheel noise and carried pose: modelled


def test_pairs_are_drawn_a_third_from_each_stratum():
    model = build_model(SMALL)
    by = strata(model)
    pairs = draw_pairs(model, 30, np.random.default_rng(1))
    assert [int(np.isin(pairs, by[k]).sum()) for k in by] == [10, 10, 10]
    assert len(set(pairs.tolist())) == 30
    s, a = by["grid-blocked"] // 4, by["grid-blocked"] % 4
    assert (model.next_state[s, a] == s).all()


def test_at_exact_every_primitive_and_the_optimal_policy_agree():
    model = build_model(SMALL)
    r = crosscheck(SMALL, model, parse_fidelity("exact"), CrosscheckOptions(pairs=18),
                   {"optimal": grid_optimal_policy(model)})
    assert r["repeats"] == 1 and r["strata"]["all"]["pairs"] == 18
    # (not every move the grid blocks bumps here: the grid's clearance blocks cells the disc
    # reaches; both simulators agree on which)
    assert r["strata"]["grid-blocked"]["p_bump_ours"] > 0.5
    assert r["strata"]["all"]["bump_agree"] == 1.0 and r["strata"]["all"]["class_agree"] == 1.0
    p = r["policies"]["optimal"]
    assert p["p_goal_rnhql"] == p["p_goal_irsim"] == 1.0
    assert p["primitives_rnhql"] == p["primitives_irsim"] == model.distance_to_goal[model.start]


def test_at_noisy_the_outcome_distributions_agree():
    model = build_model(SMALL)
    r = crosscheck(SMALL, model, parse_fidelity("noisy"), CrosscheckOptions(pairs=12, repeats=4,
                                                                             seed=3))
    a = r["strata"]["all"]
    assert r["primitives"] == 48 and a["bump_agree"] >= 0.9 and a["tv"] <= 0.2, a


def test_the_command_writes_its_figures_and_refuses_what_it_cannot_check(tmp_path, capsys):
    out = tmp_path / "cc.json"
    assert main(["crosscheck", "paper-40", "--pairs", "6", "--json", str(out)]) == 0
    got = json.loads(out.read_text())
    assert got["pairs"] == 6 and got["strata"]["all"]["bump_agree"] == 1.0
    assert "bump-or-not agrees" in capsys.readouterr().out
    assert main(["crosscheck", "paper-40", "--fidelity", "uncalibrated"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "wheel_ratio_sigma" in err[0] and "Fix:" in err[0]
    assert main(["crosscheck", "paper-40", "--pairs", "0"]) == 2


def test_without_irsim_the_command_says_how_to_install_it(monkeypatch, capsys):
    import matplotlib

    monkeypatch.setitem(sys.modules, "irsim", None)  # import irsim raises ImportError
    backend = matplotlib.get_backend()
    assert main(["crosscheck", "paper-40", "--pairs", "3"]) == 2
    err = capsys.readouterr().err
    assert "pip install 'rnhql[crosscheck]'" in err and "Traceback" not in err
    assert matplotlib.get_backend() == backend
