"""The full scenario check: start and goal free for the inflated robot, and joined.

Separate from :func:`sim.scenario.validate_shape` (pure data checks) because it
rasterises the scenario (:mod:`sim.grid.raster`), which needs the scenario's types.
"""

from __future__ import annotations

from sim.errors import ScenarioError
from sim.grid.raster import rasterise
from sim.scenario import Scenario, validate_shape


def validate(sc: Scenario, names: dict[str, str] | None = None) -> None:
    """Full validation: shape, start/goal free for the inflated robot, goal reachable.

    ``names`` renames the start/goal fields in messages (for a bare ``.map`` the
    user gave them on the command line, in the Moving AI frame).
    """
    names = names or {"start": "start", "goal": "goal"}
    validate_shape(sc)
    blocked, _, dist = rasterise(sc)
    for fld, (ix, iy) in (("start", sc.start), ("goal", sc.goal)):
        if blocked[iy, ix]:
            raise ScenarioError(sc.source, names[fld], f"cell ({ix}, {iy}) (x right, y up) is "
                                "blocked for the robot "
                                f"(radius {sc.robot.radius_m} m + clearance "
                                f"{sc.robot.clearance_m} m overlaps an obstacle, map cell or "
                                "wall)", "move it to a free cell or move the obstacle")
    if dist[sc.start[1] * sc.nx + sc.start[0]] < 0:
        raise ScenarioError(sc.source, names["goal"], "cannot be reached from the start by the "
                            "inflated robot",
                            "remove or move obstacles to open a route, or move start/goal")
