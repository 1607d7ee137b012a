"""The fidelity ladder's tables (:mod:`scenarios.studies.ladder.continuous_vs_grid`): how
well the grid predicts each rung (rho, MMRV, the predictive mark, the control variates),
P(G) and primitives per method and rung, and every figure. Registered with
:mod:`scenarios.artifacts.tables` on import."""

from __future__ import annotations

import math
import statistics
from typing import Any

from scenarios.artifacts.tables import _q, renderer, row_renderer
from sim.physics.fidelity import parse_fidelity


@renderer("ladder")
def ladder_table(d: dict[str, Any]) -> str:
    """The fidelity ladder: how well the grid predicts each rung (rank correlation), P(G)
    and primitives per method and rung (trained at the rung, and transferred from the grid)
    against V*, then every figure per map, rung, method and where it was trained."""
    if "rungs" not in d:  # artifacts written before the predictivity and V* were kept
        return ladder_full(d)
    return "\n".join([ladder_predictivity(d), ladder_compact(d, physics=True),
                      ladder_compact(d, physics=False), "#### Every figure", "",
                      ladder_full(d)])


def _rho(p: dict[str, Any]) -> str:
    if p["rho"] is None:
        return "— (no spread)"
    ci = p["ci95"]
    return f"{p['rho']:+.2f} [{ci[0]:+.2f}, {ci[1]:+.2f}]" if ci else f"{p['rho']:+.2f}"


def _mmrv(p: dict[str, Any], digits: int) -> str:
    ci = p.get("mmrv_ci95")
    v = f"{p['mmrv']:.{digits}f}"
    return f"{v} [{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]" if ci else v


_LADDER_FIGURES = (("deployed", "deployed [primitives]", 1), ("p_goal", "P(G)", 2),
                   ("learning", "learning [steps]", 1))


def _v_star(d: dict[str, Any], c: dict[str, Any]) -> str:
    opt = c["optimum"]
    exact = next((r["physics_opt"] for r in d["rows"] if r["map"] == c["map"]
                  and r["physics_opt"]), None)
    return ("— (hidden state: not Markov in cells)" if opt is None
            and parse_fidelity(c["rung"]).hidden_state else
            f"1 · {exact} (the physics world's BFS route)" if opt is None and exact
            and c["rung"] == "exact" else "—" if opt is None else
            f"{opt['p_goal_within_budget']:.3f} · {opt['expected_primitives']:.1f}")


def ladder_predictivity(d: dict[str, Any]) -> str:
    """Spearman's rho of the methods' ranks, grid vs rung, per map and rung; with MMRV, the
    predictive mark and the control-variate table where the artifact has them."""
    rungs = d["rungs"]
    if "mmrv" not in rungs[0]["predictivity"]["deployed"]:
        return _ladder_rho_only(d)
    lines = ["#### Does the grid rank the methods as the rung does? (SRCC and MMRV)", "",
             "Per figure: Spearman's ρ between the methods' order in the grid (grid-trained "
             "runs, the grid's own figures) and at the rung (runs trained and driven there), "
             "then the mean maximum rank violation (MMRV, SIMPLER; in the figure's units: how "
             "much worse at the rung a method the grid ranked better can be), each with a 95 % "
             "bootstrap interval over seeds (`scenarios/studies/ladder/predictivity.py`). "
             "✓: the rung is *predictive* of the figure on the point values, ρ ≥ 0.85 and MMRV "
             "within one seed spread (the median over methods of the rung's interquartile "
             "range of seeds); ✓✓: on the intervals too, ρ's lower end ≥ 0.85 and MMRV's upper "
             "end within the spread (the bootstrap resamples seeds, each bringing its grid run "
             "and its rung run: the two are paired). "
             "*Deployed*: expected primitives of the final policy from S, a miss costing the "
             "episode budget; *P(G)*: its chance of reaching G; *learning*: mean training "
             "episode length. — (no spread): a world cannot tell the methods apart.", "",
             "| map | rung | " + " | ".join(f"ρ {t} | MMRV {t}" for _, t, _ in _LADDER_FIGURES)
             + " | V* at the rung: P*(G) · E[primitives] |",
             "|---|---|" + "---|---|" * len(_LADDER_FIGURES) + "---|"]
    for c in rungs:
        pr = c["predictivity"]
        cells = [f"{_rho(pr[f])} | {_mmrv(pr[f], k)}{_mark(pr[f])}"
                 for f, _, k in _LADDER_FIGURES]
        lines.append(f"| {c['map']} | {c['rung']} | " + " | ".join(cells)
                     + f" | {_v_star(d, c)} |")
    lines += ["", _first_not_predictive(rungs), "", _control_variates(rungs)]
    return "\n".join(lines) + "\n"


def _mark(p: dict[str, Any]) -> str:
    """✓ on the point values, ✓✓ on the intervals too (an artifact without the interval
    mark shows the point mark only)."""
    if not p["predictive"]:
        return ""
    return " ✓✓" if p.get("predictive_interval") else " ✓"


def _first_not_predictive(rungs: list[dict[str, Any]]) -> str:
    """Per map, the first rung (in the study's order) not predictive of where a policy
    ends up (deployed and P(G))."""
    out = []
    for m in dict.fromkeys(c["map"] for c in rungs):
        miss = next((c["rung"] for c in rungs if c["map"] == m and not all(
            c["predictivity"][f]["predictive"] for f in ("deployed", "p_goal"))), None)
        out.append(f"{m}: {miss}" if miss else f"{m}: none (every rung predictive)")
    return ("The first rung where the grid stops predicting the deployed policy (deployed "
            "and P(G) both ✓ up to it): " + "; ".join(out) + ".")


def _control_variates(rungs: list[dict[str, Any]]) -> str:
    """The grid as a control variate for the rung's seeds, per map and rung."""
    lines = ["#### The grid as a control variate for the rung's seeds", "",
             "Seed k's grid run and rung run share the seed's streams. Where their figures "
             "correlate (r), the rung's mean corrected by the grid's has variance "
             "(1 − r²)(n − 2)/(n − 3) times the plain mean's, β estimated from the same n "
             "seeds (so below r² ≈ 1/(n − 2) nothing is saved), and only with the grid's "
             "mean pinned by many cheap grid seeds (Sim2Val, SureSim), **which this study "
             "does not run: the saving is hypothetical**. A method whose r has a 95 % "
             "interval (Fisher's z) covering 0 shows no correlation and no saving. Per "
             "figure: the median over methods of r² (range over methods) · the rung seeds "
             "that would give the interval of the study's n plain seeds (median over "
             "methods; no saving shown: n) · how many methods show a saving.", "",
             "| map | rung | " + " | ".join(t for _, t, _ in _LADDER_FIGURES) + " |",
             "|---|---|" + "---|" * len(_LADDER_FIGURES)]
    for c in rungs:
        cells = []
        for f, _, _ in _LADDER_FIGURES:
            cv = list(c["predictivity"][f]["control_variate"].values())
            if not cv:
                cells.append("—")
                continue
            red = [v["variance_reduction"] for v in cv]
            need = float(statistics.median([v["seeds_with_grid"] for v in cv]))
            shown = ("" if "saving_shown" not in cv[0] else
                     f" · {sum(v['saving_shown'] for v in cv)}/{len(cv)}")
            cells.append(f"{statistics.median(red):.2f} ({min(red):.2f}–{max(red):.2f}) · "
                         f"{need:g} of {cv[0]['seeds']}{shown}")
        lines.append(f"| {c['map']} | {c['rung']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _ladder_rho_only(d: dict[str, Any]) -> str:
    """The table of artifacts written before MMRV and the control variates were kept."""
    lines = ["#### Does the grid rank the methods as the rung does? (SRCC)", "",
             "Spearman's ρ between the methods' order in the grid (grid-trained runs, the "
             "grid's own figures) and at the rung (runs trained and driven there), with a 95 % "
             "bootstrap interval over seeds (`scenarios/studies/ladder/predictivity.py`). "
             "*Deployed*: expected primitives of the final policy from S, a miss costing the "
             "episode budget; *learning*: mean training episode length. 1: the grid orders "
             "the methods exactly as the rung does; — (no spread): one of the two worlds "
             "cannot tell the methods apart (every median equal).", "",
             "| map | rung | ρ deployed | ρ learning | V* at the rung: P*(G) · E[primitives] |",
             "|---|---|---|---|---|"]
    for c in d["rungs"]:
        lines.append(f"| {c['map']} | {c['rung']} | {_rho(c['predictivity']['deployed'])} | "
                     f"{_rho(c['predictivity']['learning'])} | {_v_star(d, c)} |")
    return "\n".join(lines) + "\n"


def ladder_compact(d: dict[str, Any], physics: bool) -> str:
    """P(G) median · primitives median per map x method (rows) and rung (columns)."""
    rows = [r for r in d["rows"] if (r["trained"] != "grid") == physics]
    rungs = list(dict.fromkeys(r["rung"] for r in rows))
    title = ("Trained at the rung" if physics else
             "Trained in the grid, driven at the rung (transfer)")
    lines = [f"#### {title}: P(G) · primitives", "",
             "Median over seeds of each seed's share of drives reaching G · mean primitives "
             "of those drives (— none reached G); reliable seeds (P(G) ≥ 0.98) after the "
             "slash.", "",
             "| map | method | " + " | ".join(rungs) + " |",
             "|---|---|" + "---|" * len(rungs)]
    for m in dict.fromkeys(r["map"] for r in rows):
        for method in dict.fromkeys(r["method"] for r in rows if r["map"] == m):
            cells = []
            for rung in rungs:
                r = next((x for x in rows if x["map"] == m and x["method"] == method
                          and x["rung"] == rung), None)
                if r is None:
                    cells.append("")
                    continue
                prims = "—" if r["primitives"][0] is None else f"{r['primitives'][0]:.1f}"
                cells.append(f"{r['p_goal'][0]:.2f} · {prims} / {r['reliable']}")
            lines.append(f"| {m} | {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def ladder_full(d: dict[str, Any]) -> str:
    """Every figure: one row per map, rung, method and where it was trained."""
    rows = d["rows"]
    best: dict[tuple[str, str], float] = {}
    for r in rows:
        if r["metres"][0] is not None:
            k = (r["map"], r["rung"])
            best[k] = min(best.get(k, math.inf), r["metres"][0])
    n = max((r["rollouts"] for r in rows), default=0)
    lines = [
        "Each row: a method trained in the grid (its final greedy policy then *driven* at "
        "the rung: transfer) or in physics at the rung. Every final policy is driven from S "
        f"at the rung (once at `exact`, {n} times above it, each drive its own noise "
        "stream); figures are median [q25, q75] over seeds of each seed's mean over its "
        "drives. *P(G)*: share of drives reaching G; *reliable*: seeds with P(G) ≥ 0.98; "
        "*primitives*, *driven*, *sim time*: over the drives that reached G; *vs best*: "
        "that median over the best at this map and rung; */ continuous*: over the disc's "
        "any-angle optimum (Theta*); *aliasing*: share of (cell, action) pairs with more "
        f"than one next cell ({d['repeats']} drives each).", "",
        "| map | rung | aliasing | method | trained in | P(G) | reliable | primitives | "
        "driven (m) | vs best | / continuous | sim time to G (s) | contacts per drive | "
        "contacts per training episode |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        med = r["metres"][0]
        vs = "—" if med is None else f"{med / best[(r['map'], r['rung'])]:.3f}"
        ratio = "—" if r["ratio"][0] is None else f"{r['ratio'][0]:.3f}"
        tc = "—" if r["train_contacts"][0] is None else _q(r["train_contacts"], 2)
        lines.append(
            f"| {r['map']} | {r['rung']} | {r['aliasing']:.3f} | {r['method']} | "
            f"{r['trained']} | {_q(r['p_goal'], 2)} | {r['reliable']}/{r['seeds']} | "
            f"{_q(r['primitives'], 1, '—')} | {_q(r['metres'], 1, '—')} | {vs} | {ratio} | "
            f"{_q(r['sim_time'], 1, '—')} | {_q(r['contacts'], 1)} | {tc} |")
    maps = list(dict.fromkeys(r["map"] for r in rows))
    lines += ["", "Optima per map: " + "; ".join(
        f"{m}: grid {next(r['grid_opt'] for r in rows if r['map'] == m)} moves, physics "
        f"(exact) {_physics_opt(rows, m)} moves, continuous "
        + next(("—" if r["cont"] is None else f"{r['cont']:.2f} m")
               for r in rows if r["map"] == m) for m in maps) + "."]
    return "\n".join(lines) + "\n"


def _physics_opt(rows: list[dict[str, Any]], m: str) -> str:
    return next((str(r["physics_opt"]) for r in rows if r["map"] == m and r["physics_opt"]),
                "—")


@renderer("primitives")
def primitives_table(d: dict[str, Any]) -> str:
    """What one primitive does at each rung (:mod:`scenarios.studies.ladder.primitives`):
    outcomes, time, end pose, and the bumper re-firing against the grid's count."""
    def mm(q: list[float] | None) -> list[float | None]:
        return [None if q is None else v * 1000.0 for v in (q or [None] * 3)]

    def pct(x: float | None) -> str:
        return "—" if x is None else f"{100 * x:.0f} %"

    head = ("| map | rung | reached | bumped | timed out | s per primitive | along-track "
            "[mm] | cross-track [mm] | \\|cross\\| p95 [mm] | \\|heading\\| p95 [°] | "
            "P(bump \\| bumped before) | P(bump \\| moved before) | grid blocks it |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in d["rows"]:
        lines.append(
            f"| {r['map']} | `{r['preset']}` | {pct(r['reached'])} | {pct(r['bumped'])} | "
            f"{pct(r['timeout'])} | {_q(r['seconds'], 1)} | {_q(mm(r['end_along_m']), 1)} | "
            f"{_q(mm(r['end_cross_m']), 1)} | {1000 * r['end_cross_p95_m']:.1f} | "
            f"{math.degrees(r['end_heading_p95_rad']):.1f} | {pct(r['rebump'])} | "
            f"{pct(r['bump_after_move'])} | {pct(r['grid_blocks_after_bump'])} |")
    note = (f"\n\n{d['robots']} robots × {d['moves']} uniformly random primitives per (map, "
            "rung), each robot with its own noise stream, its pose carried from move to move "
            f"as the rung says; `timeout_s` = {d['timeout_s']:g} s. End pose: every primitive "
            "that did not bump, against the target cell's centre and the action's heading "
            "(median [quartiles]). *Grid blocks it*: of the moves right after a bump, the "
            "share the grid itself blocks from the cell the robot is in (the count a bumper "
            "that never re-fires would give, up to where the contact left the robot).")
    arc = d.get("blind_arc")
    if arc:
        q = arc["cross_track_over_arc"]
        on_arc = all(abs(v - 1.0) <= 0.01 for v in q)
        note += (f"\n\nA blind drive {'ends on' if on_arc else 'curves less than'} the arc it "
                 f"stands for: a noise-free open-loop drive of {arc['length_m']:g} m with a "
                 f"per-run wheel-ratio bias ends {q[0]:.2f} [{q[1]:.2f}, {q[2]:.2f}] of the "
                 f"continuous arc's cross-track error ({arc['robots']} robots, median "
                 "[quartiles]). ")
        note += ("Each period's twist is held along the chord of the arc it turns through, "
                 "from the step the joints hand it on (`sim.physics.motion."
                 "held_twist_velocity`), so a held twist ends each period on its arc."
                 if on_arc else
                 "Each period's twist follows the heading at the period's start, one physics "
                 "step late: open-loop figures are optimistic by that much; with feedback the "
                 "controller corrects it within the primitive.")
    return head + "\n".join(lines) + note + "\n"


@renderer("crosscheck")
def crosscheck_one(d: dict[str, Any]) -> str:
    return crosscheck_rows([d])


@row_renderer("crosscheck")
def crosscheck_rows(ds: list[dict[str, Any]]) -> str:
    """``rnhql crosscheck``: this physics against IR-SIM, per (scenario, rung)."""
    def f(x: float | None, digits: int = 3) -> str:
        return "—" if x is None else f"{x:.{digits}f}"

    lines = ["| scenario | fidelity | pairs × drives | bump or not agrees | mean \\|P(bump) "
             "gap\\| | outcome class agrees | total variation | where the grid blocks: "
             "class agrees | policy: P(G) here / IR-SIM | primitives to G here / IR-SIM |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for d in ds:
        a, blocked = d["strata"]["all"], d["strata"]["grid-blocked"]
        pol = "; ".join(f"{n}: {p['p_goal_rnhql']:.2f} / {p['p_goal_irsim']:.2f}"
                        for n, p in d["policies"].items()) or "—"
        prim = "; ".join(f"{f(p['primitives_rnhql'], 1)} / {f(p['primitives_irsim'], 1)}"
                         for p in d["policies"].values()) or "—"
        lines.append(f"| {d['scenario']} | `{d['fidelity']}` | {d['pairs']} × {d['repeats']} | "
                     f"{f(a['bump_agree'])} | {f(a['bump_gap'])} | {f(a['class_agree'])} | "
                     f"{f(a['tv'])} | {f(blocked['class_agree'])} | {pol} | {prim} |")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- learn on the grid, finish
#                                                                  at the rung (warm_start)


def _ratio(warm: list[float | None], scratch: list[float | None]) -> str:
    """Warm's median robot primitives to reach (a)'s P(G) as a share of scratch's."""
    w, s = warm[0], scratch[0]
    if w is None:
        return "warm never"
    if s is None:
        return "scratch never"
    return "—" if s == 0 else f"{w / s:.0%}"


@renderer("warm-start")
def warm_start_table(d: dict[str, Any]) -> str:
    """Per rung, map and method: (a) the grid's policy driven at the rung, (b) trained at the
    rung from scratch, (c) pretrained in the grid then trained at the rung (P(G) at the
    largest budget, median [q25, q75] over seeds); c minus the better of a and b, paired by
    seed, with its 95 % bootstrap interval; robot primitives to stably reach (a)'s P(G) and
    the best P(G) any arm reached in the seed."""
    top = d["budgets"][-1]
    material = d.get("material", 0.05)
    lines = [f"P(G) of the final policy driven 50 times at the rung, median [q25, q75] over "
             f"seeds; (a) after {d['grid_episodes']} grid episodes, (b) and (c) after {top} "
             f"episodes at the rung ((c) after the same grid phase as (a)). **c − better**: "
             f"the median over seeds of (c) minus the arm of (a) and (b) with the higher median "
             f"(named), with the 95 % bootstrap interval of that median; called higher or lower "
             f"only when the interval excludes 0 and the difference is at least {material:.2f} "
             f"(about one standard error of a 50-drive P(G) near 0.9). **Reach**: robot "
             f"primitives from which P(G) stays within {d['reach_slack']:.2f} of a target at "
             f"every later budget ({', '.join(map(str, d['budgets']))} episodes at the rung; "
             "(c) starts at 0 with the grid's policy), median [q25, q75] over seeds with "
             "`never` as infinitely many, and the seeds that got there; the target is (a)'s "
             "P(G), or the best P(G) any arm reached in that seed (**best**). **Share**: (c)'s "
             "median robot primitives to the best as a share of (b)'s.", "",
             "| rung | map | method | (a) grid's policy | (b) rung only | (c) grid, then rung | "
             "c − better [95 % CI] | reach (a): (c) · (b) | best P(G) | reach best: (c) · (b) "
             "| share |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in d["rows"]:
        diff = r["c_minus_better"]

        def reach(key: str, r: dict[str, Any] = r) -> str:
            x = r[key]
            return f"{_q(x['q'])} ({x['reached']}/{x['seeds']})"

        lines.append(
            f"| `{r['rung']}` | {r['map']} | {r['name']} | {_q(r['a_p_goal'], 2)} | "
            f"{_q(r['b_p_goal'], 2)} | {_q(r['c_p_goal'], 2)} | "
            f"{diff[0]:+.2f} [{diff[1]:+.2f}, {diff[2]:+.2f}] vs ({r['better_of_ab']}): "
            f"{r['verdict']} | {reach('reach_warm')} · {reach('reach_scratch')} | "
            f"{_q(r['best_p_goal'], 2)} | {reach('reach_best_warm')} · "
            f"{reach('reach_best_scratch')} | "
            f"{_ratio(r['reach_best_warm']['q'], r['reach_best_scratch']['q'])} |")
    return "\n".join(lines) + "\n"


def warm_start_verdicts(d: dict[str, Any]) -> str:
    """The study's findings in figures: per rung, the map x method cells where continued
    learning at the rung ended (c) higher or lower than the better of (a) and (b)."""
    out = []
    for rung in dict.fromkeys(r["rung"] for r in d["rows"]):
        rows = [r for r in d["rows"] if r["rung"] == rung]

        def cells(v: str, rows: list[dict[str, Any]] = rows) -> str:
            named = [f"{r['name']} on {r['map']}" for r in rows if r["verdict"] == v]
            return f"{len(named)}" + (f" ({', '.join(named)})" if named else "")

        same = sum(r["verdict"] in ("no evidence of a difference",
                                    "within the grading's resolution") for r in rows)
        out.append(f"- at `{rung}`, of {len(rows)} map × method cells, (c) ends higher than "
                   f"the better of (a) and (b) in {cells('higher')}, lower in "
                   f"{cells('lower')}, and the same within the seeds' interval or the "
                   f"grading's resolution in {same}")
    return "\n".join(out) + "\n"


def warm_start_sentence(d: dict[str, Any]) -> str:
    """The README's sentence: what the grid saves at the rungs where it holds, and whether
    continued learning at a rung helps or hurts the grid's policy where it breaks."""
    parts = []
    for rung in dict.fromkeys(r["rung"] for r in d["rows"]):
        rows = [r for r in d["rows"] if r["rung"] == rung]
        kept = sum(r["reach_warm"]["q"][0] == 0 for r in rows)
        scratch = [r["reach_scratch"]["q"][0] for r in rows
                   if r["reach_scratch"]["q"][0] is not None]
        never = len(rows) - len(scratch)
        n = {v: sum(r["verdict"] == v for r in rows) for v in ("higher", "lower")}
        cost = (f"from scratch a median of {statistics.median(scratch):,.0f} robot primitives "
                f"where it gets there at all ({len(scratch)} cells; {never} never within "
                f"{d['budgets'][-1]} episodes)" if scratch else
                f"from scratch no cell reaches it within {d['budgets'][-1]} episodes")
        parts.append(f"at `{rung}` the grid's policy is kept from the first primitive on "
                     f"{kept} of {len(rows)} map × method cells ({cost}); continued learning "
                     f"ends higher than the better of the grid's policy and the rung alone "
                     f"on {n['higher']} cell{'s' * (n['higher'] != 1)} and lower on "
                     f"{n['lower']}")
    return ("**Learn on the grid, finish on the robot** ([docs/ladder.md](docs/ladder.md"
            "#how-much-robot-time-does-the-grid-save)): pretrained "
            f"{d['grid_episodes']} episodes in the grid, then trained at the rung, "
            + "; ".join(parts) + ".\n")
