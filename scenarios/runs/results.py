"""The ``results.json`` contract, its summary statistics and ``summary.md``.

``results.json`` (a contract for scripts; ``version`` 2)::

    {
      "version": 2, "rnhql_version": str,
      "scenario": {name, source, size_cells, start, goal, rewards: {scheme, goal, bump, step}},
      "world": "grid" | "physics" | "grid,physics",
      "fidelity": the physics fidelity's label ("exact", "noisy", ...) or null (grid only),
      "fidelity_knobs": {"name", "wheel_noise" [relative sigma per wheel per control period],
                         "carried_pose" [bool], "bumper_travel_m" [m],
                         "wheel_ratio_sigma" [-], "wheelbase_sigma" [-], "open_loop" [bool],
                         "localisation" [bool], "odometry_rot_rot" [rad^2/rad^2],
                         "odometry_rot_trans" [rad^2/m^2], "odometry_trans_trans" [m^2/m^2],
                         "odometry_trans_rot" [m^2/rad^2], "fix_every" [primitives],
                         "fix_sigma_m" [m], "fix_sigma_rad" [rad]} or null (every field of
                         sim.physics.fidelity.Fidelity; records from before the ladder's rungs hold
                         the first four),
      "physics_grading": how physics runs were graded (rollouts per test and final) or null,
      "optimum_at_fidelity": V* above exact {"expected_primitives", "p_goal_within_budget",
                             "budget", "tolerance"} or null (physics runs then carry
                             "optimal_at_fidelity": their drives match it),
      "episodes": int,
      "optimal_route_length": int,            # BFS moves S -> G on the grid model
      "runs": [ {"key", "method", "method_name", "seed", "world", "fidelity", "config",
                 "optimal_route_length" (of the world the run was graded in),
                 "episodes_to_stable_optimal" (int | null: first greedy test from which every
                    later one is optimal), "episodes_to_optimal" (int | null: first hit),
                 "optimal_test_fraction" (last 10 % of tests), "final_route_length" (int,
                 -1 = G not reached), "final_route_optimal", "final_route",
                 "epsilon_route_length" (median of epsilon-greedy rollouts from S, null if
                 most miss G), "success_rate", "reward_per_step" (total return / total
                 steps), "reward_per_step_last_10pct", "wall_time_s", "env_steps",
                 "optimal_action_fraction", "steps_per_episode" [int],
                 "return_per_episode" [float], "wall_time_per_episode_s" [float],
                 "test_episodes" [int], "test_route_length" [int],
                 physics runs: "final_policy" {"rollouts", "p_goal", "p_goal_ci95",
                 "primitives_mean", "primitives_median", "contacts_mean", "bumps_mean",
                 "metres_mean", "sim_time_s_mean"} (the final greedy policy driven from S in
                 the run's own world: once at exact, 50 times above it; there the route
                 lengths are median primitives over drives), ...} ],
      "summary": {method: {world: {figure: {"median", "q25", "q75", "ci95"}, ...,
                                   "optimal_route_fraction", "reached_goal_fraction",
                                   "seeds"}}}
    }

Quantiles everywhere are :func:`quantile` (type 7, ``null`` = never sorts last).
``ci95`` is ``[lo, hi]``, the 95 % percentile-bootstrap interval of the median over seeds
(:func:`scenarios.runs.statistics.bootstrap_ci`, 5000 resamples, a fixed seed, so the same
runs give the same interval); ``null`` (never) counts as +infinity there too and an end
that is infinite is written ``null``; ``ci95`` is ``null`` with no values. Added within
version 2: readers of ``median``/``q25``/``q75`` are unaffected.
Version 1 had ``reward_per_step`` as a per-episode list and ranked by first hits.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from learning.methods.registry import shown_name
from scenarios.runs.statistics import (
    LEVEL,
    N_RESAMPLES,
    Estimate,
    generator,
    probability_of_improvement,
    quantile,
    seed_stats,
)
from sim.files import atomic_write_text

RESULTS_VERSION = 2
RELIABLE_P_GOAL = 0.98  # a final policy "reaches G reliably" at this P(G) over its drives
SUMMARY_FIGURES = ("episodes_to_stable_optimal", "episodes_to_optimal", "optimal_test_fraction",
                   "final_route_length", "epsilon_route_length", "success_rate",
                   "reward_per_step", "reward_per_step_last_10pct", "wall_time_s", "env_steps",
                   "optimal_action_fraction")


def _ladder_knob_text(knobs: dict) -> str:
    """The bias, open-loop and localisation knobs of a summary's fidelity line, where set."""
    parts = []
    if knobs.get("wheel_ratio_sigma") or knobs.get("wheelbase_sigma"):
        parts.append(f"per-run bias sigma E_d {knobs['wheel_ratio_sigma']}, "
                     f"E_b {knobs['wheelbase_sigma']}")
    if knobs.get("open_loop"):
        parts.append("open-loop primitives")
    if knobs.get("localisation"):
        parts.append("localisation from odometry (alphas "
                     + ", ".join(str(knobs[k]) for k in (
                         "odometry_rot_rot", "odometry_rot_trans", "odometry_trans_trans",
                         "odometry_trans_rot"))
                     + (f"), a fix every {knobs['fix_every']} primitives ({knobs['fix_sigma_m']}"
                        f" m, {knobs['fix_sigma_rad']} rad)" if knobs.get("fix_every")
                        else "), no fixes"))
    return "".join(f", {p}" for p in parts)

def summarise(runs: list[dict[str, Any]]) -> dict[str, dict[str, dict[str, Any]]]:
    groups: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for r in runs:
        groups[(r["method"], r["world"])].append(r)
    out: dict[str, dict[str, dict[str, Any]]] = defaultdict(dict)
    for (method, world), rs in groups.items():
        entry: dict[str, Any] = {f: seed_stats([r.get(f) for r in rs]) for f in SUMMARY_FIGURES}
        # a route that never reaches G has no length: rank it as infinitely long
        entry["final_route_length"] = seed_stats([r["final_route_length"] if
                                              r["final_route_length"] >= 0 else None for r in rs])
        entry["reached_goal_fraction"] = float(np.mean([r["final_route_length"] >= 0
                                                        for r in rs]))
        entry["optimal_route_fraction"] = float(np.mean([r["final_route_optimal"] for r in rs]))
        entry["seeds"] = len(rs)
        pols = [r.get("final_policy") for r in rs]
        if all(p is not None for p in pols):  # physics: the final policy's drives
            entry["final_policy_p_goal"] = seed_stats([p["p_goal"] for p in pols])
            entry["final_policy_reliable_fraction"] = float(np.mean(
                [p["p_goal"] >= RELIABLE_P_GOAL for p in pols]))
            entry["final_policy_primitives_mean"] = seed_stats([p["primitives_mean"]
                                                            for p in pols])
            entry["final_policy_contacts_mean"] = seed_stats([p["contacts_mean"] for p in pols])
            entry["final_policy_rollouts"] = int(pols[0]["rollouts"])
            if all("optimal_at_fidelity" in r for r in rs):
                entry["optimal_at_fidelity_fraction"] = float(np.mean(
                    [r["optimal_at_fidelity"] for r in rs]))
        out[method][world] = entry
    return dict(out)


def _fmt(stat: dict[str, float | None] | None, digits: int = 0, missing: str = "never") -> str:
    if stat is None:
        return "–"
    def one(v: float | None) -> str:
        return missing if v is None else f"{v:.{digits}f}"
    return f"{one(stat['median'])} [{one(stat['q25'])}, {one(stat['q75'])}]"


def _fmt_ci(stat: dict[str, Any] | None, digits: int = 0, missing: str = "never") -> str:
    """The median's ``ci95`` as ``[lo, hi]`` (``–`` in results written before it existed)."""
    ci = (stat or {}).get("ci95")
    if ci is None:
        return "–"
    return "[" + ", ".join(missing if v is None else f"{v:.{digits}f}" for v in ci) + "]"


def summary_markdown(results: dict[str, Any], method_order: list[str] | None = None) -> str:
    """A human report: one row per method and world, then the honest verdict on RNH-QL."""
    summ = results["summary"]
    methods = method_order or list(summ)
    rw = results["scenario"].get("rewards")
    scheme = (f"rewards `{rw['scheme']}` (goal {rw['goal']:g}, bump {rw['bump']:g}, free step "
              f"{rw['step']:g})" if rw else "rewards as in the scenario")
    fid = results.get("fidelity")
    knobs = results.get("fidelity_knobs") or {}
    knob_text = (": wheel_noise {wheel_noise} (relative, per wheel per control period), "
                 "carried_pose {carried_pose}, bumper_travel_m {bumper_travel_m} m"
                 .format(**knobs) if {"wheel_noise", "carried_pose", "bumper_travel_m"}
                 <= set(knobs) else "")
    knob_text += _ladder_knob_text(knobs)
    world = f"{results['world']}" + (f" (physics fidelity `{fid}`{knob_text})" if fid else "")
    share = results["scenario"].get("s_start_share") or 0.0
    starts = (f", {share:.0%} of episodes start at S (the rest on random free cells)"
              if share > 0 else "")
    lines = [f"# {results['scenario']['name']}: {results['episodes']} episodes, "
             f"world {world}, {scheme}{starts}",
             "",
             f"Optimal route S -> G: {results['optimal_route_length']} moves (BFS). "
             "Figures are median [25th, 75th percentile] over seeds (type-7 quantiles). "
             "*Stable optimal*: episodes at the first greedy test from which every later "
             "test is optimal; *first optimal*: the first optimal test (a secondary figure); "
             "`never` sorts last; `no G` = the final greedy route from S does not reach the "
             "goal. *ε-route*: median length of 20 ε-greedy rollouts from S (the paper's own "
             "test). Reward per step = total return / total steps. *95 % CI*: percentile "
             f"bootstrap interval of the median over seeds ({N_RESAMPLES} resamples, fixed "
             "seed; `never` counts as infinitely many episodes). In the verdict, *P(A better "
             "than B)* is the probability of improvement: the share of (seed of A, seed of "
             "B) pairs in which A's seed does better on the ranked figure (ties ½), with its "
             "95 % bootstrap interval over seeds; an interval containing 0.5 is no evidence "
             "of a difference.",
             "",
             *(["Config overrides (`--set`): " + "; ".join(
                 f"{m}: " + ", ".join(f"{k}={v:g}" for k, v in o.items())
                 for m, o in results["overrides"].items()), ""]
               if results.get("overrides") else []),
             "Cells: median [25th, 75th percentile] over seeds, but the 95 % CI column "
             "(the median's bootstrap interval).",
             "",
             "| method | world | seeds | final route optimal | stable optimal after | "
             "its median's 95 % CI | first optimal | final route length | ε-route | "
             "success rate | reward / step | wall time (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for m in methods:
        for world, e in summ.get(m, {}).items():
            lines.append(
                f"| {shown_name(m)} | {world} | {e['seeds']} | "
                f"{e['optimal_route_fraction']:.0%} | "
                f"{_fmt(e['episodes_to_stable_optimal'])} | "
                f"{_fmt_ci(e['episodes_to_stable_optimal'])} | "
                f"{_fmt(e['episodes_to_optimal'])} | "
                f"{_fmt(e['final_route_length'], missing='no G')} | "
                f"{_fmt(e['epsilon_route_length'], missing='no G')} | "
                f"{_fmt(e['success_rate'], 2)} | {_fmt(e['reward_per_step'], 3)} | "
                f"{_fmt(e['wall_time_s'], 2)} |")
    lines += _policy_table(summ, methods, fid, results.get("optimum_at_fidelity"))
    lines += _robot_time_table(results.get("runs", []), methods)
    lines += ["", *verdict(results)]
    return "\n".join(lines) + "\n"


def _policy_table(summ: dict[str, Any], methods: list[str], fid: str | None,
                  optimum: dict[str, Any] | None = None) -> list[str]:
    """Physics runs: the final policy driven in the world it trained in."""
    rows = [(m, e) for m in methods for w, e in summ.get(m, {}).items()
            if w == "physics" and "final_policy_p_goal" in e]
    if not rows:
        return []
    n = rows[0][1]["final_policy_rollouts"]
    out = ["", f"Physics final policies, each driven {n} time(s) from S at fidelity "
           f"`{fid or 'exact'}` (own noise stream per drive, common across methods); "
           "above `exact` the route lengths above are the median primitives of these drives. "
           f"*Reliable*: seeds whose P(G) ≥ {RELIABLE_P_GOAL}. Primitives: mean over the "
           "drives that reached G."
           + (f" The yardstick at this fidelity, V*(S) (`rnhql optimum`): "
              f"{optimum['expected_primitives']:.2f} expected primitives, P(G within "
              f"{optimum['budget']}) {optimum['p_goal_within_budget']:.3f}; *optimal at F*: "
              "seeds whose drives match it (P(G) within 0.05, mean primitives within "
              "max(1, 5 %))." if optimum else ""), "",
           "| method | P(G) | reliable seeds | optimal at F | primitives | contacts per drive |",
           "|---|---|---|---|---|---|"]
    for m, e in rows:
        at_f = e.get("optimal_at_fidelity_fraction")
        out.append(f"| {shown_name(m)} | {_fmt(e['final_policy_p_goal'], 2)} | "
                   f"{e['final_policy_reliable_fraction']:.0%} | "
                   f"{'–' if at_f is None else f'{at_f:.0%}'} | "
                   f"{_fmt(e['final_policy_primitives_mean'], 1, missing='no G')} | "
                   f"{_fmt(e['final_policy_contacts_mean'], 1)} |")
    return out


def _robot_time_table(runs: list[dict[str, Any]], methods: list[str]) -> list[str]:
    """Physics runs: each phase in its own currency. A run pretrained in the grid (or at a
    lower rung) shows that phase's episodes and moves, and its policy's P(G) here before the
    robot drove; every physics run its robot primitives and robot seconds."""
    def q(values: list[float], digits: int = 0) -> str:
        return _fmt({"median": quantile(values, 0.5), "q25": quantile(values, 0.25),
                     "q75": quantile(values, 0.75)}, digits) if values else "–"

    rows = []
    for m in methods:
        mine = [r for r in runs if r.get("method") == m and r.get("world") == "physics"]
        if not mine:
            continue
        pre = [r["pretrain"] for r in mine if r.get("pretrain")]
        first = "–"
        if pre:
            where = pre[0]["world"] if pre[0]["world"] == "grid" else f"`{pre[0]['fidelity']}`"
            first = (f"{q([p['episodes'] for p in pre])} episodes in {where}, "
                     f"{q([p['env_steps'] for p in pre])} moves")
        rows.append(f"| {shown_name(m)} | {first} | "
                    f"{q([p['policy']['p_goal'] for p in pre], 2) if pre else '–'} | "
                    f"{q([r['env_steps'] for r in mine])} | "
                    f"{q([r['robot_seconds'] for r in mine if 'robot_seconds' in r], 1)} |")
    if not rows:
        return []
    return ["", "Robot time, phase by phase (median [25th, 75th percentile] over seeds): the "
            "first phase of a warm-started run (`--pretrain`, `--init`) and its policy's P(G) "
            "here before the robot drove; then this world's robot primitives and simulated "
            "robot seconds.", "",
            "| method | first phase | its policy here: P(G) | robot primitives | robot seconds |",
            "|---|---|---|---|---|", *rows]


RANKING = ("most seeds optimal, then fewest episodes to a stable optimal route, then most seeds "
           "reaching G, then highest training success rate")


def _score(e: dict[str, Any]) -> tuple[float, float, float, float]:
    """Lexicographic rank, see RANKING (lower is better)."""
    med = e["episodes_to_stable_optimal"]["median"]
    return (-e["optimal_route_fraction"], math.inf if med is None else med,
            -e["reached_goal_fraction"], -(e["success_rate"]["median"] or 0.0))


OURS = ("rnh-ql", "rnh-ql+")  # the methods the verdict speaks for


def _name(method: str) -> str:
    """RNH-QL by its name (as the verdict always has); every other method as tables show it
    (:func:`shown_name`)."""
    return "RNH-QL" if method == "rnh-ql" else shown_name(method)


def ranked_figure(summ_world: dict[str, dict[str, Any]]) -> tuple[str, bool, str]:
    """The per-seed figure a world's ranking is decided on: (run key, lower is better, label).

    Episodes to a stable optimal route (``null`` = never, the worst) while any method has
    an optimal seed: a seed without an optimal final route never got a stable one, so
    this one figure carries the ranking's first two keys. With no optimal seed anywhere
    every seed ties on it, and the training success rate (the ranking's last key) is used.
    """
    if any(e["optimal_route_fraction"] > 0 for e in summ_world.values()):
        return ("episodes_to_stable_optimal", True,
                "episodes to a stable optimal route (never = last)")
    return "success_rate", False, "training success rate"


def improvement(results: dict[str, Any], world: str, a: str, b: str) -> Estimate | None:
    """P(a better than b) in ``world`` on :func:`ranked_figure` over the seeds in
    ``results["runs"]``, with its 95 % bootstrap interval (seeded, so reproducible);
    ``None`` without per-seed runs for both."""
    figure, lower, _ = ranked_figure({m: e[world] for m, e in results["summary"].items()
                                      if world in e})
    runs = results.get("runs") or []

    def seeds(m: str) -> list[Any]:
        return [r.get(figure) for r in runs if r.get("method") == m and r.get("world") == world]

    x, y = seeds(a), seeds(b)
    if not x or not y:
        return None
    return probability_of_improvement(x, y, rng=generator(), lower_is_better=lower)


def _outcome(a: str, b: str, est: Estimate) -> str:
    if est.contains(0.5):
        return "no evidence of a difference"
    return f"{_name(a) if est.lo > 0.5 else _name(b)} is better"


def _qualifier(ours: str, ests: dict[str, Estimate]) -> str:
    """What P(improvement) says about ``ours`` against each other method, as a clause."""
    better = [m for m, e in ests.items() if e.lo > 0.5]
    worse = [m for m, e in ests.items() if e.hi < 0.5]
    none = [m for m, e in ests.items() if e.contains(0.5)]
    better, worse, none = ([_name(m) for m in ms] for ms in (better, worse, none))
    parts = ([f"{_name(ours)} is better than {', '.join(better)}"] if better else []) + \
            ([f"no evidence of a difference from {', '.join(none)}"] if none else []) + \
            ([f"{', '.join(worse)} {'is' if len(worse) == 1 else 'are'} better"]
             if worse else [])
    return (f"; by P({_name(ours)} better) and its {LEVEL * 100:g} % CI: " + "; ".join(parts)
            if parts else "")


def _comparison_lines(results: dict[str, Any], world: str,
                      ests: dict[tuple[str, str], Estimate]) -> list[str]:
    """One sub-item per (ours, other) pair: P(ours better) [CI] and what it says."""
    label = ranked_figure({m: e[world] for m, e in results["summary"].items()
                           if world in e})[2]
    out = []
    for (a, b), est in ests.items():
        n_a = sum(1 for r in results["runs"] if r.get("method") == a and r.get("world") == world)
        n_b = sum(1 for r in results["runs"] if r.get("method") == b and r.get("world") == world)
        out.append(f"  - {_name(a)} vs {_name(b)}: P({_name(a)} better) = {est.value:.2f}, "
                   f"{LEVEL * 100:g} % CI [{est.lo:.2f}, {est.hi:.2f}] on {label}, "
                   f"{n_a} × {n_b} seeds: {_outcome(a, b, est)}.")
    return out


def verdict(results: dict[str, Any]) -> list[str]:
    """Say plainly, per world, whether RNH-QL beat every other method, and whether the
    seeds are evidence of it: the rank on medians (:data:`RANKING`), then, where
    ``results["runs"]`` holds the seeds, the probability of improvement of RNH-QL (and of
    RNH-QL+) over each other method with its 95 % bootstrap interval ("no evidence of a
    difference" when that interval contains 0.5)."""
    summ = results["summary"]
    lines = []
    worlds = sorted({w for m in summ.values() for w in m})
    for world in worlds:
        scored = {m: _score(e[world]) for m, e in summ.items() if world in e}
        best = min(scored.values())
        leaders = [shown_name(m) for m in sorted(m for m, sc in scored.items() if sc == best)]
        none_optimal = all(summ[m][world]["optimal_route_fraction"] == 0 for m in scored)
        ests: dict[tuple[str, str], Estimate] = {}
        for ours in (m for m in OURS if m in scored):
            for other in scored:
                if other == ours or (other, ours) in ests:
                    continue
                est = improvement(results, world, ours, other)
                if est is not None:
                    ests[(ours, other)] = est
        qual = _qualifier("rnh-ql", {b: e for (a, b), e in ests.items() if a == "rnh-ql"})
        if none_optimal:
            lines.append(f"- {world}: no method's final greedy route from S is optimal in any "
                         f"seed within {results['episodes']} episodes.")
        if none_optimal and "rnh-ql" in scored:  # a "win" here would only be on the rest
            pos = 1 + sum(sc < scored["rnh-ql"] for sc in scored.values())
            tied = [shown_name(m) for m in sorted(m for m, sc in scored.items()
                                                  if m != "rnh-ql" and sc == scored["rnh-ql"])]
            lines.append(f"- {world}: on the rest of the ranking ({RANKING}) RNH-QL ranks "
                         f"{pos} of {len(scored)}"
                         + (f", tied with {', '.join(tied)}" if tied else "")
                         + (f"; best: {', '.join(leaders)}" if "rnh-ql" not in leaders else "")
                         + qual + ".")
        elif "rnh-ql" not in scored:
            lines.append(f"- {world}: best: {', '.join(leaders)}.")
        elif leaders == ["rnh-ql"]:
            lines.append(f"- {world}: RNH-QL ranks first ({RANKING}){qual}.")
        elif "rnh-ql" in leaders:
            lines.append(f"- {world}: RNH-QL ties for first with "
                         f"{', '.join(m for m in leaders if m != 'rnh-ql')}{qual}.")
        else:
            pos = 1 + sum(sc < scored["rnh-ql"] for sc in scored.values())
            lines.append(f"- {world}: RNH-QL does NOT win: it ranks {pos} of {len(scored)}; "
                         f"best: {', '.join(leaders)} ({RANKING}){qual}.")
        lines += _comparison_lines(results, world, ests)
    return lines


def dumps_by_line(doc: dict[str, Any]) -> str:
    """``doc`` as JSON with each top-level field, and each element of a top-level list (a
    run), on a line of its own: readable and diffable by run, and encoded by json's C
    encoder (``indent`` falls back to the pure-Python one: 5 s of the main command's tail
    for a 100-run results.json)."""
    lines = []
    for i, (key, value) in enumerate(doc.items()):
        head = f"{json.dumps(key)}: "
        comma = "," if i < len(doc) - 1 else ""
        if isinstance(value, list) and value:
            rows = ",\n  ".join(json.dumps(v) for v in value)
            lines.append(f" {head}[\n  {rows}\n ]{comma}")
        else:
            lines.append(f" {head}{json.dumps(value)}{comma}")
    return "{\n" + "\n".join(lines) + "\n}\n"


def write_results(out_dir: str | Path, results: dict[str, Any],
                  method_order: list[str] | None = None) -> None:
    out = Path(out_dir)  # the tool's own names: a link planted there is replaced, not followed
    atomic_write_text(out / "results.json", dumps_by_line(results), follow=False)
    atomic_write_text(out / "summary.md", summary_markdown(results, method_order), follow=False)
