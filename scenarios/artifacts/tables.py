"""The kinds of artifact (:mod:`scenarios.artifacts`), in one list (:data:`KINDS`): each
registered under its kind (the artifact's name up to its first dot) by the function that
renders its Markdown, with what else the tool knows of it (whether its figures are wall
times; a renderer of several artifacts as one table's rows)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Kind:
    """One kind of artifact."""

    render: Callable[[dict[str, Any]], str]  # one artifact's data -> Markdown
    timed: bool = False  # its figures include wall times: a busy machine is named
    render_rows: Callable[[list[dict[str, Any]]], str] | None = None  # several as one table


KINDS: dict[str, Kind] = {}  # the one list of artifact kinds


def renderer(kind: str, timed: bool = False
             ) -> Callable[[Callable[[dict[str, Any]], str]], Callable]:
    """Register ``kind`` with the function that renders one artifact of it."""
    def deco(fn: Callable[[dict[str, Any]], str]) -> Callable:
        KINDS[kind] = Kind(fn, timed)
        return fn
    return deco


def _q(v: list[float | None], digits: int = 0, missing: str = "never") -> str:
    """``median [q25, q75]``; ``None`` or infinity reads ``missing``."""
    def one(x: float | None) -> str:
        return missing if x is None or not math.isfinite(x) else f"{x:.{digits}f}"
    return f"{one(v[0])} [{one(v[1])}, {one(v[2])}]"


@renderer("physics-grading")
def physics_grading(d: dict[str, Any]) -> str:
    lines = [f"{d['scenario']} at `{d['fidelity']}`, {d['episodes']} episodes, rewards "
             f"`{d['rewards']}`; each final greedy policy driven {d['drives']} times from S "
             "in the world it trained in (median [q25, q75] over seeds).", "",
             "| method | seeds with P(G) ≥ 0.98 | P(G) | primitives to G (mean) | "
             "contacts per drive | independent P(G) | agree |",
             "|---|---|---|---|---|---|---|"]
    for m, e in d["methods"].items():
        lines.append(f"| {m} | {e['reliable']}/{e['seeds']} | {_q(e['p_goal'], 2)} | "
                     f"{_q(e['primitives'], 1, 'no G')} | {_q(e['contacts'], 1)} | "
                     f"{_q(e['independent_p_goal'], 2)} | {e['agree']}/{e['seeds']} |")
    return "\n".join(lines) + "\n"


@renderer("reward-design")
def reward_design(d: dict[str, Any]) -> str:
    """Every method x reward scheme x discount: optimal seeds · median episodes to a stable
    optimal route; the value-iteration facts as sentences the study computed."""
    lines = [f"On `{d['scenario']}`, {d['seeds']} seeds × {d['episodes']} episodes per cell "
             "(optimal seeds / seeds · median episodes to a stable optimal route, omitted "
             "when the median seed never gets there):", "",
             "| method | " + " | ".join(d["columns"]) + " |",
             "|---|" + "---|" * len(d["columns"])]
    for m, row in d["cells"].items():
        cells = []
        for c in d["columns"]:
            e = row[c]
            med = e["stable"][0]
            cells.append(f"{e['optimal']}/{e['seeds']}"
                         + ("" if med is None or not math.isfinite(med) else f" · {med:.0f}"))
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    lines += ["", "What value iteration says of each scheme (computed by the study):", "",
              *d["sentences"]]
    return "\n".join(lines) + "\n"


@renderer("optimum", timed=True)
def optimum(d: dict[str, Any]) -> str:
    """V* of one scenario at a fidelity, beside the exact optimum and its driven check."""
    v = "inf" if d["v_star"] is None else f"{d['v_star']:.2f}"
    dr = d["driven"]
    driven = "–" if dr is None else (
        f"{dr['primitives_mean']:.2f} primitives, P(G) {dr['p_goal']:.3f} "
        f"[{dr['p_goal_ci95'][0]:.3f}, {dr['p_goal_ci95'][1]:.3f}], "
        f"{dr['contacts_mean']:.2f} contacts ({dr['rollouts']} drives)")
    exact = d["exact"] if d["exact"] >= 0 else "no G"
    return ("| scenario, fidelity | V\\*(S) | P(G) ≤ budget | exact optimum | its policy "
            "driven | states | drives | build |\n|---|---|---|---|---|---|---|---|\n"
            f"| {d['scenario']}, `{d['fidelity']}` | {v} | {d['p_goal']:.3f} (≤ {d['budget']}) | "
            f"{exact} | {driven} | {d['states']:,} | {d['drives']:,} | "
            f"{d['build_s']:.0f} s |\n")


@renderer("plain-learner", timed=True)
def plain_learner(d: dict[str, Any]) -> str:
    """A plain learner's cost per step (Python, and a numba ``@jitclass`` where measured),
    and the compiled runs' pace beside it."""
    g, ph = d["grid"], d["physics"]
    jit = "jitclass port" in g
    head = "| | compiled `st-ql` | Python port |" + (" `@jitclass` port |" if jit else "") + \
        " compiled `st-ql` in a sweep with the port(s) |\n"
    return (f"On `{d['scenario']}` (goal-only): ports of ST-QL to the plain-learner protocol "
            f"against the compiled `st-ql`, {d['episodes']} episodes from scratch, best of "
            f"{d['repeats']}; physics at `exact`, {ph['seeds']} runs of {ph['episodes']} "
            "episodes per method, one worker, primitives per second of each run's own "
            "training time.\n\n" + head + "|---|---|---|" + ("---|" if jit else "") + "---|\n"
            f"| grid env steps/s | {g['st-ql']:,.0f} | {g['python port']:,.0f} "
            f"({g['slowdown']:.0f}x slower) |"
            + (f" {g['jitclass port']:,.0f} ({g['jitclass port'] / g['st-ql']:.0%}) |" if jit
               else "") + " |\n"
            f"| physics primitives/s | {ph['st-ql alone']:,.0f} | {ph['python port']:,.0f} |"
            + (f" {ph['jitclass port']:,.0f} ({ph['jitclass port'] / ph['st-ql alone']:.0%}) |"
               if jit else "") + f" {ph['st-ql beside the port']:,.0f} |\n"
            + _batched_rows(d))


def _batched_rows(d: dict[str, Any]) -> str:
    """The batched ports' rows, where the artifact measured them."""
    b = d.get("batched")
    if b is None:
        return ""
    g, ph = d["grid"], d["physics"]
    fast = d.get("block draws")
    if fast is None:
        return (f"\nThe numpy port written batched (one call per step for all its runs), "
                f"{b['seeds']} runs in one lock-step batch, over the batch's wall time:\n\n"
                "| | batched port | Python port (one run) | compiled `st-ql` |\n"
                "|---|---|---|---|\n"
                f"| grid env steps/s | {b['grid']:,.0f} | {g['python port']:,.0f} | "
                f"{g['st-ql']:,.0f} |\n"
                f"| physics primitives/s | {b['physics']:,.0f} | {ph['python port']:,.0f} | "
                f"{ph['st-ql alone']:,.0f} |\n\n"
                f"The batch runs at {b['grid'] / g['python port']:.1f}x the per-run port's pace "
                f"in the grid and {b['physics'] / ph['python port']:.1f}x in physics.\n")
    wide = fast["wide"]
    return (f"\nST-QL written batched in numpy (one call per step for all its runs), "
            f"{b['seeds']} runs in one lock-step batch, over the batch's wall time: the port "
            "that draws what `st-ql` draws (run for run equal to it), and the port written "
            "for numpy's speed (each run draws its numbers in blocks from its own stream):"
            "\n\n| | batched, `st-ql`'s draws | batched, block draws | Python port (one run) "
            "| compiled `st-ql` |\n|---|---|---|---|---|\n"
            f"| grid env steps/s | {b['grid']:,.0f} | {fast['grid']:,.0f} | "
            f"{g['python port']:,.0f} | {g['st-ql']:,.0f} |\n"
            f"| physics primitives/s | {b['physics']:,.0f} | {fast['physics']:,.0f} | "
            f"{ph['python port']:,.0f} | {ph['st-ql alone']:,.0f} |\n\n"
            f"With {wide['seeds']} runs in its batch, the block-draws port steps the grid at "
            f"{wide['grid']:,.0f} env steps/s ({wide['grid'] / fast['grid']:.1f}x its pace "
            f"with {fast['seeds']}): numpy's cost is per call, not per run.\n")


def plain_learner_sentence(d: dict[str, Any]) -> str:
    """How much slower the ports are than the compiled learner, in each world."""
    g, ph = d["grid"], d["physics"]
    text = (f"On the grid the Python port is {g['slowdown']:.0f}x slower than the fused kernel "
            "(two Python calls and numpy's small-array overhead per step); in physics at "
            f"`exact` it is {ph['st-ql alone'] / ph['python port']:.0f}x slower "
            f"({ph['python port']:,.0f} primitives/s against {ph['st-ql alone']:,.0f}): the "
            "compiled learner trains inside the fused physics step, while the port is called "
            "once per robot per primitive.")
    if "jitclass port" in g:
        text += (f" Written as a `@jitclass`, the port runs in compiled loops in both worlds "
                 "(the grid's episodes in one loop, its physics runs in the fused physics "
                 "step the compiled methods train in): the grid at "
                 f"{g['jitclass port'] / g['st-ql']:.0%} of the compiled `st-ql`, physics at "
                 f"{ph['jitclass port'] / ph['st-ql alone']:.0%} "
                 f"({ph['jitclass port']:,.0f} primitives/s).")
    return text + "\n"


@renderer("own-learner", timed=True)
def own_learner(d: dict[str, Any]) -> str:
    """A user's learner (the batched torch DQN example) against rnh-ql+ in both worlds."""
    lines = [f"`{d['scenario']}`, {d['episodes']} episodes, rewards `{d['rewards']}`, optimal "
             f"route {d['optimal_route_length']} moves; median [quartiles] over seeds:", "",
             "| method | world | final route optimal | stable optimal after | success rate "
             "| training time [s] |", "|---|---|---|---|---|---|"]
    for r in d["rows"]:
        lines.append(f"| {r['name']} | {r['world']} | {r['optimal']}/{r['seeds']} | "
                     f"{_q(r['stable_optimal'])} | {_q(r['success_rate'], 2)} | "
                     f"{_q(r['train_s'], 1)} |")
    return "\n".join(lines) + "\n"


@renderer("memory", timed=True)
def memory(d: dict[str, Any]) -> str:
    """Peak RSS and checkpoint size per method and map size."""
    sizes = d["sizes"]
    lines = [f"{d['kind']} maps, one training run of {d['episodes']} episodes saved to a "
             "checkpoint per cell, each in a fresh process, kernels compiled beforehand; peak "
             f"RSS · checkpoint (the imports alone take {d['floor_mb']:.0f} MB):", "",
             "| method | " + " | ".join(f"{n}²" for n in sizes) + " |",
             "|---|" + "---|" * len(sizes)]
    for m, row in d["methods"].items():
        lines.append(f"| {m} | " + " | ".join(
            f"{row[str(n)][0]:.0f} MB · {row[str(n)][1]:.1f} MB" for n in sizes) + " |")
    return "\n".join(lines) + "\n"


@renderer("ablation")
def ablation(d: dict[str, Any]) -> str:
    """The ablation on the suite: optimal seeds · median episodes to a stable optimal route
    (— never) per variant and map, and how many maps reach ``min_seeds`` optimal seeds."""
    maps, k = d["maps"], d["min_seeds"]
    lines = [f"Rewards `{d['rewards']}`, {d['seeds']} seeds × {d['episodes']} episodes; `*` = "
             "maps generated from seeds nobody tuned on; cells: optimal seeds · median "
             "episodes to a stable optimal route (— never).", "",
             "| variant | " + " | ".join(m["name"] + ("*" if m["held_out"] else "")
                                       for m in maps) + f" | maps ≥ {k} |",
             "|---|" + "---|" * (len(maps) + 1)]
    for lab in d["labels"]:
        row = d["summary"].get(lab, {})
        cells, good, have = [], 0, 0
        for m in maps:
            c = row.get(m["name"])
            if c is None:
                cells.append("")
                continue
            have += 1
            good += c["optimal_seeds"] >= k
            med = c["median"]
            cells.append(f"{c['optimal_seeds']} · "
                         + ("—" if med is None or not math.isfinite(med) else f"{med:.0f}"))
        lines.append(f"| {lab} | " + " | ".join(cells) + f" | {good}/{have} |")
    return "\n".join(lines) + "\n"


@renderer("scaling", timed=True)
def scaling(d: dict[str, Any]) -> str:
    """Arenas of growing size: optimal seeds · median [q25, q75] episodes to a stable optimal
    route · median wall time per run, and each method's growth exponents."""
    sizes, seeds = d["sizes"], d["seeds"]
    first = next(iter(d["rows"].values()))
    lines = [f"Rewards `{d['rewards']}`, {seeds} seeds; columns: n × n cells (route length in "
             "moves, episode budget 60n); cells: optimal seeds / seeds · median [q25, q75] "
             "episodes to a stable optimal route · median wall time per run; exponent: slope "
             "of log median over log states, over the sizes with a finite median "
             "(episodes, wall time).", "",
             "| method | " + " | ".join(f"{q['n']}×{q['n']} ({q['route']}, {60 * q['n']})"
                                       for q in first) + " | exponent |",
             "|---|" + "---|" * (len(sizes) + 1)]
    for m, pts in d["rows"].items():
        cells = [f"{round(q['optimal'] * seeds)}/{seeds} · "
                 + _q([q["episodes"][k] for k in ("median", "q25", "q75")])
                 + f" · {q['wall']['median']:.2f} s" for q in pts]
        fit = pts[0]["fit"]
        lines.append(f"| {m} | " + " | ".join(cells) + f" | {fit['episodes']}, {fit['wall']} |")
    lines += ["", "Where most seeds reach a stable optimal route (generated from the table): "
              + "; ".join(
        _scaling_sentence(m, pts, seeds) for m, pts in d["rows"].items()) + "."]
    return "\n".join(lines) + "\n"


def _scaling_sentence(method: str, pts: list[dict[str, Any]], seeds: int) -> str:
    """Up to which size a method keeps a stable optimal route in most seeds."""
    good = [q for q in pts if q["episodes"]["median"] is not None
            and round(q["optimal"] * seeds) * 2 > seeds]
    if not good:
        return f"`{method}` at no size"
    if len(good) == len(pts):
        lo, hi = pts[0]["episodes"]["median"], pts[-1]["episodes"]["median"]
        return (f"`{method}` at every size, median {lo:.0f} to {hi:.0f} episodes "
                f"(exponent {pts[0]['fit']['episodes']})")
    last = good[-1]
    return (f"`{method}` up to {last['n']}×{last['n']} only "
            f"(median {last['episodes']['median']:.0f} episodes there)")


@renderer("scaling-maps", timed=True)
def scaling_maps(d: dict[str, Any]) -> str:
    """Generated maps, one table per size: optimal seeds / seeds · median [q25, q75]
    episodes to a stable optimal route · median wall time per run, per row and map kind."""
    out = []
    for size in sorted({p["size"] for p in d["points"]}):
        pts = [p for p in d["points"] if p["size"] == size]
        kinds = list(dict.fromkeys(p["kind"] for p in pts))
        route = {p["kind"]: p["route"] for p in pts}
        lines = ["| method | " + " | ".join(f"{k} {size}² (route {route[k]})" for k in kinds)
                 + " |", "|---|" + "---|" * len(kinds)]
        for row in dict.fromkeys(p["row"] for p in pts):
            by = {p["kind"]: p for p in pts if p["row"] == row}
            cells = []
            for k in kinds:
                p = by.get(k)
                if p is None:
                    cells.append("–")
                    continue
                q25, med, q75 = p["episodes"]
                w = p["wall"][1]
                cells.append(f"{p['optimal']}/{p['seeds']} · {_q([med, q25, q75])} · "
                             f"{w:.{2 if w < 10 else 1}f} s")
            lines.append(f"| {row} | " + " | ".join(cells) + " |")
        out.append("\n".join(lines))
    return ("Cells: optimal seeds / seeds · median [q25, q75] episodes to a stable optimal "
            "route · median wall time per run.\n\n" + "\n\n".join(out) + "\n")


@renderer("test-from-s")
def test_from_s(d: dict[str, Any]) -> str:
    """Where the greedy test from S stops, a line per seed (the held-out maps' diagnosis)."""
    return "```text\n" + "\n".join(d["lines"]) + "\n```\n"


@renderer("paper-claims", timed=True)
def paper_claims(d: dict[str, Any]) -> str:
    """The paper's claims, one by one: whether each holds here and what was measured."""
    held = sum(c["holds"] for c in d["claims"])
    lines = [f"{held} of {len(d['claims'])} claims hold ({d['seeds']} seeds × {d['episodes']} "
             f"episodes, rewards: {d['rewards']}).", "",
             "| claim | holds | measured |", "|---|---|---|"]
    lines += [f"| {c['claim']} | {'yes' if c['holds'] else '**no**'} | {c['measured']} |"
              for c in d["claims"]]
    lines += ["", "Why (value iteration on paper-50, computed by the study):", "",
              *d["value_notes"]]
    return "\n".join(lines) + "\n"


@renderer("oracle")
def oracle(d: dict[str, Any]) -> str:
    """Q-learning shaped by the best potential each feature set can hold (static)."""
    lines = [f"On `{d['scenario']}`, γ = {d['gamma']:g}, {d['episodes']} episodes; result: "
             "optimal seeds / seeds · median [q25, q75] episodes to a stable optimal route; "
             "fit error: mean absolute error of the potential against V* over free states.",
             "", "| rewards | potential | fit error | V*(S) | result |", "|---|---|---|---|---|"]
    for r in d["rows"]:
        lines.append(f"| {r['rewards']} | {r['potential']} | {r['fit_error']:.3g} | "
                     f"{r['v_star_s']:.3g} | {r['optimal']}/{r['seeds']} · {_q(r['stable'])} |")
    return "\n".join(lines) + "\n"


def row_renderer(kind: str) -> Callable[[Callable[[list[dict[str, Any]]], str]], Callable]:
    """Give the registered ``kind`` a renderer of several artifacts as one table."""
    def deco(fn: Callable[[list[dict[str, Any]]], str]) -> Callable:
        KINDS[kind] = dataclasses.replace(KINDS[kind], render_rows=fn)
        return fn
    return deco


@renderer("aliasing")
def aliasing_one(d: dict[str, Any]) -> str:
    return aliasing_rows([d])


@row_renderer("aliasing")
def aliasing_rows(ds: list[dict[str, Any]]) -> str:
    """Aliasing at several fidelities: a row each."""
    lines = ["| scenario | fidelity | (cell, action) pairs × drives | pairs with more than one "
             "next cell | mean next-cell entropy | mean bump probability |",
             "|---|---|---|---|---|---|"]
    for d in ds:
        lines.append(f"| {d['scenario']} | `{d['fidelity']}` | {d['pairs']:,} × {d['repeats']} "
                     f"| {d['multi_outcome_fraction']:.4f} | {d['mean_entropy_bits']:.4f} bits "
                     f"| {d['mean_bump_probability']:.4f} |")
    return "\n".join(lines) + "\n"


@renderer("physics-batch", timed=True)
def physics_batch(d: dict[str, Any]) -> str:
    """The batched physics world's speed: random primitives per second against robots per
    Space, and one learning run's rate and where its time goes."""
    m = d["machine"]
    maps = list(d["scaling"])
    sizes = list(d["scaling"][maps[0]])
    lines = [f"Measured on {m['cores']} cores ({m['cpu']}, Python {m['python']}; 1-minute load "
             f"{m['load_1min'][0]} before, {m['load_1min'][1]} after: other work on the "
             "machine lowers every figure). Random primitives per second on one core, by "
             "robots in one Space:", "",
             "| map | " + " | ".join(sizes) + " |", "|---|" + "---|" * len(sizes)]
    for name in maps:
        lines.append(f"| {name} | " + " | ".join(
            f"{d['scaling'][name][n]['primitives_per_s'] / 1000:.0f}k" for n in sizes) + " |")
    le = d["learning"]
    split = ", ".join(f"{k} {100 * v:.0f} %" for k, v in
                      sorted(le["split_fraction_of_training"].items(), key=lambda kv: -kv[1]))
    lines += ["", f"A learning run as `compare --world physics` trains it ({le['runs']} runs × "
              f"{le['episodes']} episodes at `{le['fidelity']}`, one batch, one core): "
              f"**{le['primitives_per_s_training'] / 1000:.0f}k primitives/s** "
              f"({int(le['primitives']):,} primitives); time split: {split}."]
    return "\n".join(lines) + "\n"


def _took(seconds: float) -> str:
    if seconds < 1.0:
        return "under 1 s"
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


@renderer("tour", timed=True)
def tour_table(d: dict[str, Any]) -> str:
    """The short tour as a code block, each line with what to expect and its measured time."""
    own = set(d["own_file"])
    lines = ["```bash"]
    for r in d["lines"]:
        note = d["notes"][r["command"]] + (" (with your own file)" if r["command"] in own
                                           else "")
        if not r["ran"]:
            took = ""
        elif r["passed"]:
            took = f" · {_took(r['wall_s'])}"
        else:
            took = f" · FAILED here (exit {r['exit']})"
        lines.append(f"{r['command']:<49} # {note}{took}")
    ran = [r for r in d["lines"] if r["ran"]]
    total = sum(r["wall_s"] for r in ran)
    where = ("a non-editable copy (`pip install`), with a cold numba cache"
             if d["installed"] else "a clone, with numba's cache as the lines before left it")
    lines += ["```", "", f"Times: each line run in order in a fresh folder from {where} "
              f"({_took(total)} for the {len(ran)} lines; a first use of a method or of the "
              "physics world compiles its kernels once, so later lines are faster)."]
    quiet = [r for r in ran if "longest_silence_s" in r]
    if quiet:
        worst = max(quiet, key=lambda r: r["longest_silence_s"])
        lines[-1] += (f" The longest any line printed nothing, its output read as a log "
                      f"reads it (progress every 5 s): {worst['longest_silence_s']:.1f} s, "
                      f"`{worst['command']}`.")
    return "\n".join(lines) + "\n"


def main_job_sentence(d: dict[str, Any]) -> str:
    """The README's set-up step 1, timed by the tour (its first line)."""
    row = next((r for r in d["lines"] if r["command"] == d.get("main_job")), None)
    if row is None:
        return "The last tour did not time step 1's main job.\n"
    if not row.get("passed"):
        return f"Step 1's main job failed in the last tour (exit {row['exit']}).\n"
    where = "a `pip install`" if d["installed"] else "a clone"
    return (f"Step 1's main job took {_took(row['wall_s'])} after the install, from {where} "
            "on this project's 2-core machine: its first run compiles every method's kernels "
            "(numba caches them on disk, so a second run is faster).\n")
