"""A scenario script: a world of circles built in Python, rnh-ql+ against haql in the grid and
in the physics world at ``noisy``, with a recording.

Run as pasted: ``python examples/script_circles.py`` (about two minutes on 2 cores);
``RNHQL_EXAMPLE_SCALE=0.01`` shrinks the budget (CI does, to check it runs). Open the
recording with ``rnhql view recordings/pillars-20-compare.rrd``.
"""

import os

import numpy as np

from scenarios import api
from sim.scenario import Circle, Scenario

SCALE = float(os.environ.get("RNHQL_EXAMPLE_SCALE", "1"))


def pillars(seed: int = 7, n: int = 14) -> Scenario:
    """A 20 m x 20 m arena with ``n`` pillars drawn from ``seed``, S and G in opposite corners
    (a layout that blocks S, G or their connection is refused with the reason)."""
    rng = np.random.default_rng(seed)
    circles = tuple(Circle(float(x), float(y), float(r)) for x, y, r in
                    zip(rng.uniform(4, 16, n), rng.uniform(4, 16, n), rng.uniform(0.6, 1.4, n),
                        strict=True))
    return Scenario(name="pillars-20", width_m=20.0, height_m=20.0, start=(1, 1),
                    goal=(18, 18), obstacles=circles, steps_per_episode=400)


if __name__ == "__main__":  # the workers of a sweep may re-import this file
    world = pillars()
    cmp = api.compare(world, ["rnh-ql+", "haql"], worlds=["grid", "physics"],
                      fidelity="noisy", seeds=max(2, round(10 * SCALE)),
                      episodes=max(20, round(300 * SCALE)), record=True, progress=True)
    print(cmp.summary())
    for where in ("grid", "physics"):
        for method in cmp.methods:
            runs = cmp.of(method, where)
            stable = [r.episodes_to_stable_optimal for r in runs]
            found = sum(s is not None for s in stable)
            p_goal = [r.p_goal for r in runs if r.p_goal is not None]
            extra = f", median P(G) {np.median(p_goal):.2f}" if p_goal else ""
            print(f"{method} in {where}: stably optimal in {found}/{len(runs)} seeds{extra}")
    print(f"recording: {cmp.recording}  (open: rnhql view {cmp.recording})")
