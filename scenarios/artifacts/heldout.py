"""The held-out studies' tables (:mod:`scenarios.studies.maps.heldout`): the per-map table
with its rankings under it, and the finding across studies (a row per study and protocol,
each map kind's winner). Registered with :mod:`scenarios.artifacts.tables` on import.

**Ties.** A map's winner is every method with the lowest median episodes to a stable
optimal route and, among those, the most optimal seeds: all of them are named, in name
order, each with its own interval, and each counts the map as won. The study stores one
of them (the first in ``--methods`` order); which one never shows here, so nothing
rendered depends on the order of the arguments."""

from __future__ import annotations

import re
from pathlib import PurePosixPath
from typing import Any

from scenarios.artifacts.tables import renderer, row_renderer

# a scenario file's stem as the held-out studies write them: KIND-N[-sSEED][-bBRAID][-corners]
_STEM = re.compile(r"(?P<kind>.+?)-(?P<size>\d+)(?:-s\d+)?(?:-b[\d.]+)?(?P<corners>-corners)?")


def map_of(col: str) -> tuple[str, str]:
    """(kind, side) of a column's map: ``maze-w4-256 s10 (route ...)`` -> ("maze-w4", "256");
    a scenario file written by :mod:`scenarios.studies.maps.corners`
    (``.../maze-w4-256-s2027-b0.02-corners.toml``) -> ("maze-w4 corners", "256"); a
    built-in scenario ``paper-50`` -> ("paper", "50")."""
    name = col.split(" ")[0]
    if name.endswith(".toml"):
        m = _STEM.fullmatch(PurePosixPath(name).stem)
        if m:
            return m["kind"] + (" corners" if m["corners"] else ""), m["size"]
    kind, _, size = name.rpartition("-")
    return (kind, size) if kind else (name, "")


def label(col: str) -> str:
    """A column as the tables show it: a scenario file's path by its map, kind, side and
    placement (``maze-w4-256 corners s10 (route 1054)``), every other column as it is."""
    name, _, rest = col.partition(" ")
    if not name.endswith(".toml"):
        return col
    kind, size = map_of(col)
    base, _, place = kind.partition(" ")
    return f"{base}-{size}{' ' + place if place else ''} {rest}"

RANKING_NOTE = ("each method's IQM share of the episode budget spent before a stable optimal "
                "route (never: all of it; lower is better) [95 % stratified bootstrap "
                "interval], and P(the row's run spends less than the column's), averaged over "
                "the maps [95 %]:")


@renderer("heldout", timed=True)
def heldout(d: dict[str, Any]) -> str:
    """Held-out maps: a row per method, a column per map and protocol; cells
    optimal seeds / seeds · median episodes to a stable optimal route · median wall time."""
    cols = d["columns"]
    lines = [d["caption"], "", "| method | " + " | ".join(label(c) for c in cols) + " |",
             "|---|" + "---|" * len(cols)]
    for row, cells in d["rows"].items():
        lines.append(f"| {row} | " + " | ".join(cells.get(c, "–") for c in cols) + " |")
    for proto, r in d.get("ranking", {}).get("protocols", {}).items():
        order = r["order"]
        n = len(r["maps"])
        lines += ["", f"**{_protocol(proto)}**, {n} map{'s' * (n != 1)}: {RANKING_NOTE}", "",
                  "| method | IQM | " + " | ".join(f"P(< {o})" for o in order) + " |",
                  "|---|---|" + "---|" * len(order)]
        for m in order:
            lines.append(f"| {m} | {_est(r['iqm'][m], 3)} | " + " | ".join(
                "–" if o == m else _est(r["poi"][m][o], 2) for o in order) + " |")
    if d.get("ranking", {}).get("winners"):
        won = "; ".join(f"{label(c).split(' (')[0]}: {_winner(d, c)}"
                        for c in d["ranking"]["winners"])
        lines += ["", "Per map, the method with the lowest median episodes to a stable optimal "
                  "route (ties: every method with that median and as many optimal seeds, in "
                  f"name order) [95 % bootstrap interval of the median, where one won]: {won}."]
    return "\n".join(lines) + "\n"


def _protocol(proto: str) -> str:
    return "Uniform starts" if proto == "uniform" else f"{proto[1:]} % of starts from S"


def _est(v: list[float], digits: int) -> str:
    return f"{v[0]:.{digits}f} [{v[1]:.{digits}f}, {v[2]:.{digits}f}]"


def _winner(d: dict[str, Any], col: str) -> str:
    """Map ``col``'s winner, ``method optimal/seeds · median [interval]``; a tie (:func:`winners`)
    names every method in it, joined by ``=``, with the shared figures and no interval (the
    study kept one for the first it ran)."""
    w, names = d["ranking"]["winners"][col], winners(d, col)
    med = "never" if w["median"] is None else f"{w['median']:.0f}"
    if len(names) > 1:
        return f"{' = '.join(names)} {w['optimal']}/{w['seeds']} · {med} (a tie)"
    lo, hi = (("never" if v is None else f"{v:.0f}") for v in w["ci"])
    return f"{w['method']} {w['optimal']}/{w['seeds']} · {med} [{lo}, {hi}]"


def winners(d: dict[str, Any], col: str) -> list[str]:
    """Every method with the stored winner's median and optimal seeds on map ``col``, in
    name order (the module's tie rule)."""
    w = d["ranking"]["winners"][col]
    best = (float("inf") if w["median"] is None else w["median"], -w["optimal"])
    return sorted(m for m, by_map in d.get("runs", {}).items() if by_map.get(col)
                  and (_median(by_map[col]), -sum(e is not None for e in by_map[col])) == best
                  ) or [w["method"]]


@row_renderer("heldout")
def heldout_winners(ds: list[dict[str, Any]]) -> str:
    """Held-out studies as one finding: a row per study and protocol, a column per map
    kind, each cell the map's winner (:func:`_winner`), with the IQM ranking's first."""
    kinds = list(dict.fromkeys(map_of(c)[0] for d in ds for c in d["columns"]))
    lines = ["| maps | starts | " + " | ".join(kinds) + " | lowest IQM [95 %] |",
             "|---|---|" + "---|" * (len(kinds) + 1)]
    for d in (d for d in ds if "ranking" in d):  # older artifacts kept no seeds to rank
        size = map_of(d["columns"][0])[1]
        for proto, r in d["ranking"]["protocols"].items():
            won = {map_of(c)[0]: _winner(d, c) for c in r["maps"]}
            first = r["order"][0]
            starts = _protocol(proto)
            lines.append(f"| {size}² | {starts[0].lower()}{starts[1:]} | " + " | ".join(
                won.get(k, "–") for k in kinds) + f" | {first} {_est(r['iqm'][first], 2)} |")
    return "\n".join(lines) + "\n"


def heldout_summary(ds: list[dict[str, Any]]) -> str:
    """The held-out rows in words, for the prose beside the table (rendered, not typed):
    per size and protocol, who ranks first by IQM and who wins how many maps, which."""
    out = []
    for d in (d for d in ds if "ranking" in d):
        size = map_of(d["columns"][0])[1]
        for proto, r in d["ranking"]["protocols"].items():
            won: dict[str, list[str]] = {}
            for c in r["maps"]:
                for m in winners(d, c):  # a tie: a win of each
                    won.setdefault(m, []).append(map_of(c)[0])
            wins = "; ".join(f"`{m}` first on {len(ks)} of {len(r['maps'])} ({', '.join(ks)})"
                             for m, ks in sorted(won.items(), key=lambda x: (-len(x[1]), x[0])))
            starts = _protocol(proto)
            out.append(f"**{size}², {starts[0].lower()}{starts[1:]}**: `{r['order'][0]}` ranks "
                       f"first by IQM; {wins}.")
    return " ".join(out) + "\n"


REFERENCES = ("fsa-replan", "r-max", "lrta-star", "abstraction-ql")  # docs/methods.md's
LEARNER = "rnh-ql+explore"  # the tool's best learner, judged against the targets


def _median(eps: list[Any]) -> float:
    """The median of per-seed episodes, a miss counting as never (inf)."""
    s = sorted(float("inf") if e is None else float(e) for e in eps)
    mid = len(s) // 2
    return s[mid] if len(s) % 2 else (s[mid - 1] + s[mid]) / 2


def _episodes(v: float) -> str:
    return "never" if v == float("inf") else f"{v:.0f}"


def heldout_verdicts(d: dict[str, Any]) -> str:
    """The judging targets, checked from the artifact: ``rnh-ql+explore`` optimal in at
    least 9 of 10 seeds on every map, and a median no more than 1.2 x the best reference's
    + 10 episodes (the references it ran), map by map, met or missed with the figures."""
    runs = d["runs"].get(LEARNER)
    if runs is None:
        return f"({LEARNER} was not run here.)\n"
    refs = [m for m in REFERENCES if m in d["runs"]]
    cols = list(runs)
    reliable = [c for c in cols if sum(e is not None for e in runs[c]) >= 0.9 * len(runs[c])]
    missed_rel = [c.split(" (")[0] for c in cols if c not in reliable]
    met, missed = [], []
    for c in cols:
        mine = _median(runs[c])
        best_ref, best = min(((m, _median(d["runs"][m][c])) for m in refs if c in d["runs"][m]),
                             key=lambda x: (x[1], x[0]), default=(None, float("inf")))
        target = 1.2 * best + 10
        line = (f"{c.split(' (')[0]}: {_episodes(mine)} against {best_ref}'s "
                f"{_episodes(best)} (target {_episodes(target)})")
        (met if mine <= target else missed).append(line)
    rel = ("met on every map" if not missed_rel else
           f"missed on {len(missed_rel)} of {len(cols)} ({', '.join(missed_rel)})")
    return (f"**Reliability ({LEARNER} optimal in ≥ 9 of 10 seeds): {rel}.** "
            f"**Speed against the references run here ({', '.join(refs)}): met on "
            f"{len(met)} of {len(cols)} maps**" + (f"; missed on {'; '.join(missed)}"
                                                    if missed else "") + ".\n")


def _optimal(eps: list[Any]) -> int:
    return sum(e is not None for e in eps)


def fresh_verdicts(d: dict[str, Any], learner: str) -> str:
    """The fresh judging set's three verdicts (docs/studies.md, fixed before its runs),
    checked from the artifact map by map: ``learner`` (the Q-choosing rnh-ql+) optimal in at
    least 9 of 10 seeds on every map under uniform starts; the best method (the map's
    winner, :func:`winners`) within 1.2 x the best reference's median + 10 episodes on every
    map and protocol; and on the open maps the best method optimal in at least 9 of 10."""
    runs, protocols = d["runs"], d["protocols"]
    refs = [m for m in REFERENCES if m in runs]
    out = []
    mine = runs.get(learner)
    if mine is None:
        out.append(f"({learner} was not run here.)")
    else:
        uni = [c for c in mine if protocols[c] == "uniform"]
        low = [f"{label(c).split(' (')[0]} {_optimal(mine[c])}/{len(mine[c])}" for c in uni
               if _optimal(mine[c]) < 0.9 * len(mine[c])]
        out.append(f"**`{learner}` optimal in ≥ 9 of 10 seeds under uniform starts: "
                   + ("met on every map" if not low else
                      f"missed on {len(low)} of {len(uni)} ({'; '.join(low)})") + ".**")
    met, missed, open_maps = 0, [], []
    for c in d["columns"]:
        best = winners(d, c)
        b_med = _median(runs[best[0]][c])
        ref, r_med = min(((m, _median(runs[m][c])) for m in refs if c in runs[m]),
                         key=lambda x: (x[1], x[0]), default=(None, float("inf")))
        if b_med <= 1.2 * r_med + 10:
            met += 1
        else:
            missed.append(f"{label(c).split(' (')[0]}: {' = '.join(best)} {_episodes(b_med)} "
                          f"against {ref}'s {_episodes(r_med)}")
        if map_of(c)[0] == "open":
            n = _optimal(runs[best[0]][c])
            open_maps.append(f"{label(c).split(' (')[0]} {' = '.join(best)} "
                             f"{n}/{len(runs[best[0]][c])}")
    n = len(d["columns"])
    out.append(f"**The best method within 1.2 × the best reference's median + 10 episodes "
               f"({', '.join(refs)}): met on {met} of {n} maps**"
               + (f"; missed on {'; '.join(missed)}" if missed else "") + ".")
    if open_maps:
        out.append("**Open maps, the best method optimal in ≥ 9 of 10 seeds**: "
                   + "; ".join(open_maps) + ".")
    return " ".join(out) + "\n"


def head_to_head(d: dict[str, Any], a: str, b: str) -> str:
    """Method ``a`` against ``b``, per protocol: P(a's run spends less of the budget than
    b's) [95 %] from the ranking, and each map's median episodes of both (a, then b), with
    the share of a's over b's where both settle."""
    out = []
    for proto, r in d["ranking"]["protocols"].items():
        if a not in r["poi"] or b not in r["poi"][a]:
            continue
        cells = []
        for c in r["maps"]:
            ma, mb = _median(d["runs"][a][c]), _median(d["runs"][b][c])
            ratio = f" ({ma / mb:.1f} ×)" if ma < float("inf") and 0 < mb < float("inf") else ""
            cells.append(f"{map_of(c)[0]} {_episodes(ma)} against {_episodes(mb)}{ratio}")
        starts = _protocol(proto)
        out.append(f"**{starts[0].lower()}{starts[1:]}**: P(`{a}` < `{b}`) "
                   f"{_est(r['poi'][a][b], 2)}; median episodes, map by map: "
                   + "; ".join(cells) + ".")
    return " ".join(out) + "\n"


def run_times(d: dict[str, Any], method: str, limit_s: float | None = None) -> str:
    """``method``'s median wall time per run on each map of the table (the time in its
    cells): its fastest and slowest map, and how many maps are within ``limit_s`` (if
    given)."""
    times = []
    for col, cell in d["rows"].get(method, {}).items():
        m = re.search(r"([\d.]+) s$", cell)
        if m:
            times.append((float(m[1]), label(col).split(" (")[0]))
    if not times:
        return f"`{method}` has no timed runs in this table.\n"
    times.sort()
    within = "" if limit_s is None else (
        f"; within {limit_s:g} s on {sum(t <= limit_s for t, _ in times)} of "
        f"{len(times)} maps")
    return (f"`{method}`, median wall time per run: {times[0][0]:g} s ({times[0][1]}) to "
            f"{times[-1][0]:g} s ({times[-1][1]}){within}.\n")
