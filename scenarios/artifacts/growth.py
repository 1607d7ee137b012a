"""The growth study's table (:mod:`scenarios.studies.maps.growth`): episodes to a stable
optimal route per map size, each method's exponent, and the N log N yardstick's over the
same sizes. Registered with :mod:`scenarios.artifacts.tables` on import."""

from __future__ import annotations

import math
from typing import Any

from scenarios.artifacts.tables import renderer


def _cell(m: dict[str, Any], seeds: int) -> str:
    q = m["quartiles"]
    med = "never" if q[1] is None else f"{q[1]:.0f}"
    spread = "" if q[1] is None else \
        f" [{q[0]:.0f}, {'never' if q[2] is None else f'{q[2]:.0f}'}]"
    return f"{m['optimal']}/{seeds} · {med}{spread} · {m['wall_s']:.1f} s"


def _slope(xs: list[float], ys: list[float]) -> float:
    """Least-squares slope of log y against log x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    cov = sum((a - mx) * (b - my) for a, b in zip(lx, ly, strict=True))
    return cov / sum((a - mx) ** 2 for a in lx)


@renderer("growth", timed=True)
def growth(d: dict[str, Any]) -> str:
    """A row per map size: its free cells N, route, budget, and per method optimal seeds /
    seeds · median [q25, q75] episodes to a stable optimal route · median wall time; under
    it each method's exponent and the yardstick's."""
    labels, pts, seeds = d["methods"], d["points"], d["seeds"]
    lines = [f"{d['kind']} maps (map seed {d['map_seed']}), {d['protocol']} starts, "
             f"{d['rewards']} rewards, {seeds} seeds; cells: optimal seeds / seeds · median "
             "[q25, q75] episodes to a stable optimal route · median wall time per run.", "",
             "| side | free cells N | route | budget | " + " | ".join(labels) + " |",
             "|---|---|---|---|" + "---|" * len(labels)]
    for p in pts:
        lines.append(f"| {p['size']} | {p['cells']:,} | {p['route']} | {p['budget']} | "
                     + " | ".join(_cell(p["methods"][lab], seeds) for lab in labels) + " |")
    cells = [p["cells"] for p in pts]
    ex = "; ".join(f"{lab} " + ("–" if d["exponents"][lab] is None
                                 else f"{d['exponents'][lab]:.2f}") for lab in labels)
    yard = ""
    if len(cells) > 1:
        steps = _slope(cells, [n * math.log(n) for n in cells])
        sides = [p["size"] for p in pts]
        per_side = _slope(cells, [n * math.log(n) / s for n, s in zip(cells, sides, strict=True)])
        yard = (f" Over the same sizes N log N grows as N^{steps:.2f} and N log N / side "
                f"(N log N steps in episodes of about a side's steps) as N^{per_side:.2f}.")
    lines += ["", "Exponents (least-squares slope of log median episodes against log N, over "
              f"the sizes where the median seed got there): {ex}.{yard}"]
    return "\n".join(lines) + "\n"
