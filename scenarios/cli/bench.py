"""``rnhql bench``: the throughput benchmarks of :mod:`scenarios.bench`.
"""

from __future__ import annotations

import argparse
import json

from scenarios.bench import grid as bench_grid
from scenarios.bench import learners as bench


def _flat(values: dict, prefix: str = ""):
    """(key, value) pairs of a nested dict, nested keys joined with a dot."""
    for k, v in values.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", v


def _number(v) -> str:
    """Large rates in full with thousands separators (not 7e+05), small figures to 4 digits."""
    if not isinstance(v, float):
        return str(v)
    return f"{v:,.0f}" if abs(v) >= 1e4 else f"{v:.4g}"


def cmd_bench(args: argparse.Namespace) -> int:
    figures: dict = {"foundation": bench_grid.run_bench(), "learning": bench.run_bench()}
    if args.physics:
        # lazy: scenarios.bench.physics and .physics_batch cost 8 ms at startup
        from scenarios.bench import physics as bench_physics
        from scenarios.bench import physics_batch as bench_batch

        figures["physics"] = bench_physics.run_bench()
        figures["physics_batch"] = bench_batch.run_bench()
    if args.json:
        print(json.dumps(figures, indent=1))
    else:
        for section, values in figures.items():
            print(f"[{section}]")
            for k, v in _flat(values):
                print(f"  {k:<44} {_number(v)}")
    return 0
