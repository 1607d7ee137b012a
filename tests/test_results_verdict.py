"""The summary's plain verdict on RNH-QL, including the case where nothing is optimal."""

from scenarios.runs.results import verdict


def entry(opt: float, reached: float, success: float, stable=None):
    return {"optimal_route_fraction": opt, "reached_goal_fraction": reached,
            "success_rate": {"median": success},
            "episodes_to_stable_optimal": {"median": stable}}


def test_no_optimal_route_anywhere_is_not_called_a_win():
    res = {"episodes": 100, "summary": {"rnh-ql": {"grid": entry(0, 0, 0.2)},
                                        "st-ql": {"grid": entry(0, 0, 0.2)},
                                        "haql": {"grid": entry(0, 0.5, 0.3)}}}
    text = "\n".join(verdict(res))
    assert "no method's final greedy route from S is optimal" in text
    assert "ties for first" not in text and "ranks first" not in text
    assert "RNH-QL ranks 2 of 3" in text and "tied with st-ql" in text and "best: haql" in text


def test_a_real_win_and_a_loss_are_said_plainly():
    win = {"episodes": 10, "summary": {"rnh-ql": {"grid": entry(1.0, 1.0, 0.9, 50)},
                                       "st-ql": {"grid": entry(0.5, 1.0, 0.9, 80)}}}
    assert "RNH-QL ranks first" in verdict(win)[0]
    loss = {"episodes": 10, "summary": {"rnh-ql": {"grid": entry(0.1, 1.0, 0.9)},
                                        "haql": {"grid": entry(1.0, 1.0, 0.9, 30)}}}
    assert "RNH-QL does NOT win: it ranks 2 of 2; best: haql" in verdict(loss)[0]


def test_a_final_policy_is_optimal_at_a_fidelity_when_its_drives_match_v_star():
    from scenarios.runs.results import summary_markdown
    from scenarios.sweep.run import matches_optimum

    opt = {"expected_primitives": 80.0, "p_goal_within_budget": 1.0, "budget": 600,
           "tolerance": {"p_goal": 0.05, "primitives_relative": 0.05,
                         "primitives_absolute": 1.0}}
    assert matches_optimum({"p_goal": 0.96, "primitives_mean": 83.9}, opt)
    assert not matches_optimum({"p_goal": 0.94, "primitives_mean": 80.0}, opt)  # misses G
    assert not matches_optimum({"p_goal": 1.0, "primitives_mean": 84.1}, opt)  # too long
    assert not matches_optimum({"p_goal": 0.0, "primitives_mean": None}, opt)
    pol = {"rollouts": 50, "p_goal": 1.0, "primitives_mean": 80.5, "contacts_mean": 1.0}
    entry = {"seeds": 1, "optimal_route_fraction": 1.0, "final_policy_p_goal":
             {"median": 1.0, "q25": 1.0, "q75": 1.0}, "final_policy_reliable_fraction": 1.0,
             "final_policy_primitives_mean": {"median": 80.5, "q25": 80.5, "q75": 80.5},
             "final_policy_contacts_mean": {"median": 1.0, "q25": 1.0, "q75": 1.0},
             "final_policy_rollouts": pol["rollouts"], "optimal_at_fidelity_fraction": 1.0}
    for k in ("episodes_to_stable_optimal", "episodes_to_optimal", "final_route_length",
              "epsilon_route_length", "success_rate", "reward_per_step", "wall_time_s"):
        entry[k] = {"median": 1.0, "q25": 1.0, "q75": 1.0}
    entry["reached_goal_fraction"] = 1.0
    results = {"summary": {"haql": {"physics": entry}}, "world": "physics",
               "fidelity": "noisy", "fidelity_knobs": {"wheel_noise": 0.05,
                                                       "carried_pose": True,
                                                       "bumper_travel_m": 0.002},
               "scenario": {"name": "paper-50", "rewards": None}, "episodes": 10,
               "optimal_route_length": 80, "optimum_at_fidelity": opt}
    text = summary_markdown(results)
    assert "V*(S)" in text and "80.00 expected primitives" in text
    assert "| haql | 1.00 [1.00, 1.00] | 100% | 100% |" in text
    assert "bumper_travel_m 0.002 m" in text
