"""The route problem: arena, obstacles, start/goal cells, robot and reward scheme.

Frames and units: metres, x to the right, y upwards, origin at the arena's
bottom-left corner. Cells are ``(ix, iy)`` with ``ix`` the column from the left
and ``iy`` the row from the *bottom*; cell ``(ix, iy)`` covers
``[ix*c, (ix+1)*c) x [iy*c, (iy+1)*c)`` for cell size ``c``. Moving AI maps count
rows from the top; :mod:`sim.maps.movingai` converts them explicitly.

A scenario is plain frozen data. Everything derived from it (occupancy, the
tabular model, the physics world) is built by the modules that need it, so a
scenario stays cheap to copy, hash and pickle into worker processes. Loading
(TOML, ``.map``, built-ins) is :mod:`sim.scenario_io`; random layouts are
:mod:`sim.maps.layouts`; the feasibility check that rasterises is :mod:`sim.feasibility`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from sim.errors import ScenarioError

Cell = tuple[int, int]


@dataclass(frozen=True)
class Circle:
    """A static circular obstacle."""

    x_m: float  # centre x [m]
    y_m: float  # centre y [m]
    radius_m: float  # [m]


@dataclass(frozen=True)
class Robot:
    """The differential-drive disc robot."""

    radius_m: float = 0.3  # body radius [m]
    wheel_base_m: float = 0.4  # distance between the two wheels [m]
    max_wheel_speed_m_s: float = 1.0  # wheel rim speed limit [m/s]
    max_wheel_accel_m_s2: float = 4.0  # wheel rim acceleration limit [m/s^2]
    mass_kg: float = 5.0  # [kg]
    clearance_m: float = 0.05  # safety margin added to the radius when rasterising [m]

    @property
    def inflation_m(self) -> float:
        """How far an obstacle is grown for planning: radius plus clearance [m]."""
        return self.radius_m + self.clearance_m


REWARD_SCHEMES: dict[str, tuple[float, float, float]] = {
    "paper": (100.0, -1.0, 1.0),  # the paper's: +1 for every free step
    "goal-only": (100.0, -1.0, 0.0),  # a free step is worth nothing: only G pays
    "step-cost": (100.0, -1.0, -1.0),  # every step costs: shortest routes pay most
}


def move_reward(goal: float, bump: float, step: float, at_goal: bool, bumped: bool,
                moved: bool = True) -> float:
    """The route problem's reward rule for one move (:meth:`Rewards.of_moves` says why):
    ``goal`` on entering G, else ``bump`` when a contact began, else ``step`` for a move that
    left its cell, else 0. Plain Python, so compiled loops inline this same function
    (:mod:`scenarios.runs.physics_fused`) rather than a copy of the rule."""
    return goal if at_goal else bump if bumped else step if moved else 0.0


@dataclass(frozen=True)
class Rewards:
    """A reward scheme: what entering G, a bump and a free step are worth.

    ``scheme`` names a preset of :data:`REWARD_SCHEMES` (the paper's by default),
    or ``custom`` when the values differ from every preset; reports name it.
    """

    goal: float = 100.0  # on entering the goal cell (terminates)
    bump: float = -1.0  # a move into an obstacle, a blocked cell or a wall (agent stays)
    step: float = 1.0  # any other move
    scheme: str = "paper"  # preset name, or "custom"

    @classmethod
    def preset(cls, name: str, source: str = "command line",
               fld: str = "rewards.scheme") -> Rewards:
        if name not in REWARD_SCHEMES:
            raise ScenarioError(source, fld, f"unknown reward scheme {name!r}",
                                f"use one of: {', '.join(REWARD_SCHEMES)}")
        goal, bump, step = REWARD_SCHEMES[name]
        return cls(goal, bump, step, name)

    def named(self) -> Rewards:
        """The same values, ``scheme`` set to the preset they match (else ``custom``)."""
        for name, values in REWARD_SCHEMES.items():
            if (self.goal, self.bump, self.step) == values:
                return replace(self, scheme=name)
        return replace(self, scheme="custom")

    def of_moves(self, bumped, at_goal, moved=True):
        """The route problem's reward rule, for one move or an array of them: ``goal`` on
        entering G, else ``bump`` when a contact began, else ``step`` for a move that left its
        cell (``moved``), else 0 (a control period of ``rnhql/DiffDrive-v0`` that stayed in
        its cell). Every world and model reads it from here. (On the grid and at the
        ``exact`` fidelity a bump never ends in G: the robot stays. With carried pose a robot
        can touch a wall on its way into G; the move still reached G, and a model learner
        that stored it as "G, worth a bump" would replay the goal as a penalty.)"""
        if not isinstance(bumped, np.ndarray):  # one move (a single env's step): plain Python
            return move_reward(self.goal, self.bump, self.step, at_goal, bumped, moved)
        return np.where(at_goal, self.goal,
                        np.where(bumped, self.bump, np.where(moved, self.step, 0.0)))

    def label(self) -> str:
        return f"{self.scheme} (goal {self.goal:g}, bump {self.bump:g}, free step {self.step:g})"


def rewards_from_text(text: str, flag: str = "--rewards") -> Rewards:
    """``goal-only`` (a preset), or ``goal=100,bump=-1,step=0`` (missing values from the
    paper's scheme; ``scheme=NAME`` first picks another base)."""
    text = text.strip()
    if "=" not in text:
        return Rewards.preset(text, "command line", flag)
    values: dict[str, float] = {}
    base = Rewards()
    for part in text.split(","):
        key, _, value = part.partition("=")
        key = key.strip()
        if key == "scheme":
            base = Rewards.preset(value.strip(), "command line", flag)
            continue
        if key not in ("goal", "bump", "step"):
            raise ScenarioError("command line", flag, f"unknown reward {key!r}",
                                "write e.g. --rewards goal=100,bump=-1,step=0 or a preset name")
        try:
            v = float(value)
        except ValueError:
            raise ScenarioError("command line", flag, f"{key}={value!r} is not a number",
                                "write e.g. step=0") from None
        if not math.isfinite(v):
            raise ScenarioError("command line", flag, f"{key} must be finite", "use a number")
        values[key] = v
    return replace(base, **values).named()


@dataclass(frozen=True)
class Scenario:
    """One route problem, shared by the gridded and the continuous world."""

    name: str
    width_m: float  # arena width [m]
    height_m: float  # arena height [m]
    start: Cell  # start cell S (ix, iy)
    goal: Cell  # goal cell G (ix, iy)
    cell_size_m: float = 1.0  # [m]
    obstacles: tuple[Circle, ...] = ()
    blocked_cells: tuple[Cell, ...] = ()  # blocked map cells, rnhql frame
    robot: Robot = field(default_factory=Robot)
    rewards: Rewards = field(default_factory=Rewards)
    steps_per_episode: int = 600  # episode length limit [steps]
    s_start_share: float = 0.0  # share of training episodes that start at S [fraction]; the
    #                             rest start on a uniformly drawn free cell (the paper: 0)
    physics: str | None = None  # [physics] table as a --fidelity text (None: exact)
    description: str = ""
    source: str = "<python>"  # where it was loaded from, for error messages

    @property
    def nx(self) -> int:
        return round(self.width_m / self.cell_size_m)

    @property
    def ny(self) -> int:
        return round(self.height_m / self.cell_size_m)


# ---------------------------------------------------------------- validation


def finite_positive(value: float, source: str, fld: str, fix: str) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise ScenarioError(source, fld, f"must be a finite positive number, got {value!r}", fix)


# Limits that keep every array of a run in memory (a 4096 x 4096 grid is 16.8M states;
# the tool is measured up to 1024 x 1024), and an episode length a run can finish.
MAX_CELLS_PER_SIDE = 4096
MAX_STEPS_PER_EPISODE = 10_000_000
MAX_OBSTACLES = 100_000
# the largest coordinate or radius of an obstacle: 1e6 m is 250 arenas of the largest size
# (4096 cells of any sane size); beyond it squares and sums of coordinates overflow
MAX_COORDINATE_M = 1e6


def _is_cell(cell: object) -> bool:
    """Two whole numbers (ints, numpy's included; not bools, not floats that truncate)."""
    return (isinstance(cell, tuple | list) and len(cell) == 2
            and all(isinstance(v, int | np.integer) and not isinstance(v, bool) for v in cell))


def validate_shape(sc: Scenario) -> None:
    """Checks that need no rasterising: sizes, radii, cells in range."""
    src = sc.source
    finite_positive(sc.cell_size_m, src, "arena.cell_size_m", "use e.g. 1.0")
    finite_positive(sc.width_m, src, "arena.width_m", "use e.g. 50.0")
    finite_positive(sc.height_m, src, "arena.height_m", "use e.g. 50.0")
    for dim, fld in ((sc.width_m, "arena.width_m"), (sc.height_m, "arena.height_m")):
        ratio = dim / sc.cell_size_m
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 2:
            raise ScenarioError(src, fld, f"{dim} m is not a whole number (>= 2) of "
                                f"{sc.cell_size_m} m cells",
                                "choose a cell size that divides the arena")
        if round(ratio) > MAX_CELLS_PER_SIDE:
            raise ScenarioError(src, fld, f"{dim} m is {round(ratio):,} cells, more than the "
                                f"limit of {MAX_CELLS_PER_SIDE} a side",
                                "use a smaller arena or larger cells")
    if len(sc.obstacles) > MAX_OBSTACLES:
        raise ScenarioError(src, "obstacles", f"{len(sc.obstacles):,} circles, more than the "
                            f"limit {MAX_OBSTACLES:,}", "use fewer circles or a .map")
    rb = sc.robot
    for name in ("radius_m", "wheel_base_m", "max_wheel_speed_m_s", "max_wheel_accel_m_s2",
                 "mass_kg"):
        finite_positive(getattr(rb, name), src, f"robot.{name}", "use a positive number")
    if not (math.isfinite(rb.clearance_m) and rb.clearance_m >= 0):
        raise ScenarioError(src, "robot.clearance_m", f"must be >= 0, got {rb.clearance_m}",
                            "use e.g. 0.05")
    if rb.inflation_m >= sc.cell_size_m / 2:
        raise ScenarioError(src, "robot.radius_m",
                            f"robot radius + clearance ({rb.inflation_m:.3f} m) does not fit in "
                            f"a {sc.cell_size_m} m cell (must be < {sc.cell_size_m / 2} m)",
                            "shrink the robot or enlarge arena.cell_size_m")
    for i, c in enumerate(sc.obstacles):
        fld = f"obstacles.circles[{i}]"
        for v, part in ((c.x_m, "x"), (c.y_m, "y"), (c.radius_m, "radius")):
            if not math.isfinite(v) or abs(v) > MAX_COORDINATE_M:
                raise ScenarioError(src, fld, f"{part} is {v:g}, beyond the limit of "
                                    f"{MAX_COORDINATE_M:g} m", "give coordinates in the arena")
        if not (math.isfinite(c.radius_m) and c.radius_m > 0):
            raise ScenarioError(src, fld, f"radius must be a finite positive number, got "
                                f"{c.radius_m}", "give the radius in metres, e.g. 1.5")
    for fld, cell in (("start", sc.start), ("goal", sc.goal)):
        if not _is_cell(cell):
            raise ScenarioError(src, fld, f"is {cell!r}, not a cell of two whole numbers",
                                "write it as (x, y), e.g. (1, 1)")
        ix, iy = cell
        if not (0 <= ix < sc.nx and 0 <= iy < sc.ny):
            raise ScenarioError(src, fld, f"cell ({ix}, {iy}) is outside the {sc.nx}x{sc.ny} "
                                "arena", f"use 0 <= x < {sc.nx} and 0 <= y < {sc.ny}")
    if sc.start == sc.goal:
        raise ScenarioError(src, "goal", "goal equals start", "choose a different goal cell")
    cells = np.asarray(sc.blocked_cells, dtype=object).reshape(-1, 2) \
        if sc.blocked_cells else np.zeros((0, 2), dtype=np.int64)
    ok = (np.issubdtype(np.asarray(sc.blocked_cells).dtype, np.integer) and
          len(cells) == len(sc.blocked_cells) and bool(
              ((cells[:, 0] >= 0) & (cells[:, 0] < sc.nx) & (cells[:, 1] >= 0)
               & (cells[:, 1] < sc.ny)).all())) if sc.blocked_cells else True
    for i, cell in enumerate(() if ok else sc.blocked_cells):  # (the first bad one, named)
        if not _is_cell(cell) or not (0 <= cell[0] < sc.nx and 0 <= cell[1] < sc.ny):
            raise ScenarioError(src, f"blocked_cells[{i}]", f"is {cell!r}, not a cell of the "
                                f"{sc.nx}x{sc.ny} arena (negative or too large numbers would "
                                "block another cell)", f"use whole numbers 0 <= x < {sc.nx}, "
                                f"0 <= y < {sc.ny}")
    if not (isinstance(sc.steps_per_episode, int)
            and 0 < sc.steps_per_episode <= MAX_STEPS_PER_EPISODE):
        raise ScenarioError(src, "steps_per_episode", f"must be an integer in 1.."
                            f"{MAX_STEPS_PER_EPISODE:,}, got {sc.steps_per_episode!r}",
                            "use e.g. 600")
    share = sc.s_start_share
    if not (isinstance(share, int | float) and not isinstance(share, bool)
            and 0.0 <= share < 1.0):
        raise ScenarioError(src, "s_start_share", f"must be a number in [0, 1), got {share!r}",
                            "use e.g. 0.1 (one episode in ten starts at S) or 0 (the paper)")
    for name in ("goal", "bump", "step"):
        if not math.isfinite(getattr(sc.rewards, name)):
            raise ScenarioError(src, f"rewards.{name}", "must be finite", "use a number")
