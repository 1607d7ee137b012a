"""``rnhql bench``: the throughput benchmarks of :mod:`scenarios.bench`.
"""

from __future__ import annotations

import argparse
import json


def cmd_bench(args: argparse.Namespace) -> int:
    from scenarios.bench.learners import grid as bench_grid

    figures: dict = {"foundation": bench_grid.run_bench()}
    try:
        from scenarios.bench.learners import learners as bench

        figures["learning"] = bench.run_bench()
    except ImportError:
        pass
    if args.physics:
        from scenarios.bench.learners import physics as bench_physics

        figures["physics"] = bench_physics.run_bench()
    if args.json:
        print(json.dumps(figures, indent=1))
    else:
        for section, values in figures.items():
            print(f"[{section}]")
            for k, v in values.items():
                print(f"  {k:<44} {v:,.4g}" if isinstance(v, float) else f"  {k:<44} {v}")
    return 0
