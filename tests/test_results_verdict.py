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
