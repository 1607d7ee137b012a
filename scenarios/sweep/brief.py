"""What ``rnhql compare`` prints when a sweep ends: a compact table and the verdict's
headlines within 100 columns (``summary.md``, :mod:`scenarios.runs.results`, holds the full
tables and every pairwise verdict)."""

from __future__ import annotations

import textwrap
from typing import Any

from learning.methods.registry import shown_name
from scenarios.runs.results import verdict


def _ci(stat: dict[str, Any]) -> str:
    """The median's 95 % interval as ``[lo, hi]`` (``never`` for an end never reached)."""
    ci = stat.get("ci95")
    if ci is None:
        return "–"
    return "[" + ", ".join("never" if v is None else f"{v:.0f}" for v in ci) + "]"


TERMINAL_COLUMNS = 100  # what the command's own summary fits in


def summary_terminal(results: dict[str, Any], method_order: list[str] | None = None,
                     width: int = TERMINAL_COLUMNS) -> str:
    """What ``rnhql compare`` prints: a compact table (method, world, seeds whose final
    route is optimal, median episodes to a stable optimal route with its 95 % interval,
    training success, P(G) of the physics policies), then the verdict's headlines, every
    line within ``width`` columns; summary.md holds the full tables and the pairwise
    verdicts."""
    summ = results["summary"]
    methods = method_order or list(summ)
    rw = results["scenario"].get("rewards") or {}
    fid = results.get("fidelity")
    head = (f"{results['scenario']['name']}: {results['episodes']} episodes, "
            f"rewards {rw.get('scheme', 'of the scenario')}"
            + (f", physics at {fid}" if fid else "")
            + f"; optimum {results['optimal_route_length']} moves (BFS)")
    any_physics = any("final_policy_p_goal" in e for m in methods
                      for e in summ.get(m, {}).values())
    names = {m: shown_name(m) for m in methods}
    name_w = min(24, max(len("method"), *(len(n) for n in names.values())))
    cols = [("method", name_w), ("world", 7), ("optimal", 7),
            ("stable optimal after: median [95 % CI]", 38), ("success", 7)]
    if any_physics:
        cols.append(("P(G)", 4))
    rows = [" ".join(t.ljust(w) for t, w in cols).rstrip()]
    for m in methods:
        shown = names[m] if len(names[m]) <= name_w else names[m][:name_w - 1] + "…"
        for world, e in summ.get(m, {}).items():
            stat = e["episodes_to_stable_optimal"]
            med = stat.get("median")
            stable = f"{'never' if med is None else f'{med:.0f}'} {_ci(stat)}"
            cells = [shown, world, f"{round(e['optimal_route_fraction'] * e['seeds'])}/"
                     f"{e['seeds']}", stable, f"{(e['success_rate']['median'] or 0):.2f}"]
            if any_physics:
                p = (e.get("final_policy_p_goal") or {}).get("median")
                cells.append("–" if p is None else f"{p:.2f}")
            rows.append(" ".join(c.ljust(w) for c, (_, w) in zip(cells, cols,
                                                                   strict=True)).rstrip())
    headlines = [line for line in verdict(results) if line.startswith("- ")]
    wrapped = [w for line in headlines
               for w in textwrap.wrap(line, width, subsequent_indent="  ")]
    return "\n".join([*textwrap.wrap(head, width), "", *rows, "", *wrapped]) + "\n"
