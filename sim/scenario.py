"""The route problem: arena, obstacles, start/goal cells, robot and reward scheme.

Frames and units: metres, x to the right, y upwards, origin at the arena's
bottom-left corner. Cells are ``(ix, iy)`` with ``ix`` the column from the left
and ``iy`` the row from the *bottom*; cell ``(ix, iy)`` covers
``[ix*c, (ix+1)*c) x [iy*c, (iy+1)*c)`` for cell size ``c``. Moving AI maps count
rows from the top; :mod:`sim.maps` converts them explicitly.

A scenario is plain frozen data. Everything derived from it (occupancy, the
tabular model, the physics world) is built by the modules that need it, so a
scenario stays cheap to copy, hash and pickle into worker processes.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from sim.errors import ScenarioError
from sim.maps import GridMap, load_map, movingai_to_cell

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


@dataclass(frozen=True)
class Rewards:
    """Reward scheme; the default is the paper's."""

    goal: float = 100.0  # on entering the goal cell (terminates)
    bump: float = -1.0  # a move into an obstacle, a blocked cell or a wall (agent stays)
    step: float = 1.0  # any other move


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
    description: str = ""
    source: str = "<python>"  # where it was loaded from, for error messages

    @property
    def nx(self) -> int:
        return round(self.width_m / self.cell_size_m)

    @property
    def ny(self) -> int:
        return round(self.height_m / self.cell_size_m)

    @property
    def n_cells(self) -> int:
        return self.nx * self.ny


# ---------------------------------------------------------------- validation


def _finite_positive(value: float, source: str, fld: str, fix: str) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise ScenarioError(source, fld, f"must be a finite positive number, got {value!r}", fix)


def validate_shape(sc: Scenario) -> None:
    """Checks that need no rasterising: sizes, radii, cells in range."""
    src = sc.source
    _finite_positive(sc.cell_size_m, src, "arena.cell_size_m", "use e.g. 1.0")
    _finite_positive(sc.width_m, src, "arena.width_m", "use e.g. 50.0")
    _finite_positive(sc.height_m, src, "arena.height_m", "use e.g. 50.0")
    for dim, fld in ((sc.width_m, "arena.width_m"), (sc.height_m, "arena.height_m")):
        ratio = dim / sc.cell_size_m
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 2:
            raise ScenarioError(src, fld, f"{dim} m is not a whole number (>= 2) of "
                                f"{sc.cell_size_m} m cells",
                                "choose a cell size that divides the arena")
    rb = sc.robot
    for name in ("radius_m", "wheel_base_m", "max_wheel_speed_m_s", "max_wheel_accel_m_s2",
                 "mass_kg"):
        _finite_positive(getattr(rb, name), src, f"robot.{name}", "use a positive number")
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
        for v, part in ((c.x_m, "x"), (c.y_m, "y")):
            if not math.isfinite(v):
                raise ScenarioError(src, fld, f"{part} is {v}", "give finite coordinates in m")
        if not (math.isfinite(c.radius_m) and c.radius_m > 0):
            raise ScenarioError(src, fld, f"radius must be a finite positive number, got "
                                f"{c.radius_m}", "give the radius in metres, e.g. 1.5")
    for fld, (ix, iy) in (("start", sc.start), ("goal", sc.goal)):
        if not (0 <= ix < sc.nx and 0 <= iy < sc.ny):
            raise ScenarioError(src, fld, f"cell ({ix}, {iy}) is outside the {sc.nx}x{sc.ny} "
                                "arena", f"use 0 <= x < {sc.nx} and 0 <= y < {sc.ny}")
    if sc.start == sc.goal:
        raise ScenarioError(src, "goal", "goal equals start", "choose a different goal cell")
    if not (isinstance(sc.steps_per_episode, int) and sc.steps_per_episode > 0):
        raise ScenarioError(src, "steps_per_episode", f"must be a positive integer, got "
                            f"{sc.steps_per_episode!r}", "use e.g. 600")
    for name in ("goal", "bump", "step"):
        if not math.isfinite(getattr(sc.rewards, name)):
            raise ScenarioError(src, f"rewards.{name}", "must be finite", "use a number")


def validate(sc: Scenario, names: dict[str, str] | None = None) -> None:
    """Full validation: shape, start/goal free for the inflated robot, goal reachable.

    ``names`` renames the start/goal fields in messages (for a bare ``.map`` the
    user gave them on the command line, in the Moving AI frame).
    """
    names = names or {"start": "start", "goal": "goal"}
    from sim.grid import rasterise  # grid builds on scenario: import late

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


# --------------------------------------------------------------- random layouts


def random_circles(sc: Scenario, count: int, radius_min_m: float, radius_max_m: float,
                   rng: np.random.Generator, keep_clear_m: float = 1.5,
                   max_layouts: int = 100) -> tuple[Circle, ...]:
    """Draw ``count`` circles that keep S and G free and connected.

    Circles are rejected one by one if they come within ``keep_clear_m`` of the
    start or goal centre; a finished layout that disconnects S from G is dropped
    whole and redrawn (rare at the densities used here, and cheaper than a BFS
    per circle). Deterministic for a given generator state.
    """
    c = sc.cell_size_m
    keep = [((ix + 0.5) * c, (iy + 0.5) * c) for ix, iy in (sc.start, sc.goal)]
    for _ in range(max_layouts):
        circles: list[Circle] = []
        tries = 0
        while len(circles) < count and tries < 100 * count:
            tries += 1
            r = float(rng.uniform(radius_min_m, radius_max_m))
            x = float(rng.uniform(0.0, sc.width_m))
            y = float(rng.uniform(0.0, sc.height_m))
            if all(math.hypot(x - kx, y - ky) > r + sc.robot.inflation_m + keep_clear_m
                   for kx, ky in keep):
                circles.append(Circle(x, y, r))
        candidate = replace(sc, obstacles=sc.obstacles + tuple(circles))
        try:
            validate(candidate)
        except ScenarioError:
            continue
        return tuple(circles)
    raise ScenarioError(sc.source, "obstacles.random", f"no connected layout in {max_layouts} "
                        "tries", "use fewer or smaller circles")


def chain(start_m: tuple[float, float], end_m: tuple[float, float], radius_m: float,
          spacing_m: float) -> tuple[Circle, ...]:
    """Circles of one radius every ``spacing_m`` along a segment: a wall made of posts."""
    (x0, y0), (x1, y1) = start_m, end_m
    n = max(1, math.floor(math.hypot(x1 - x0, y1 - y0) / spacing_m))
    return tuple(Circle(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, radius_m)
                 for k in range(n + 1))


# ------------------------------------------------------------------ TOML loading


class _Table:
    """A TOML table that remembers which keys were read, to reject unknown ones."""

    def __init__(self, data: dict[str, Any], path: str, source: str) -> None:
        if not isinstance(data, dict):
            raise ScenarioError(source, path or "<top>", f"expected a table, got {data!r}",
                                "see scenarios/builtin/paper-50.toml for the layout")
        self.data, self.path, self.source, self.used = data, path, source, set()

    def _fld(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def get(self, key: str, kind: type | tuple[type, ...], default: Any = None,
            required: bool = False) -> Any:
        self.used.add(key)
        if key not in self.data:
            if required:
                raise ScenarioError(self.source, self._fld(key), "is missing",
                                    f"add '{key} = ...' (see scenarios/builtin/paper-50.toml)")
            return default
        value = self.data[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
            names = kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)
            raise ScenarioError(self.source, self._fld(key), f"expected {names}, got {value!r}",
                                f"write {key} as a {names}")
        return value

    def table(self, key: str) -> _Table:
        return _Table(self.get(key, dict, {}), self._fld(key), self.source)

    def cell(self, key: str, required: bool = True) -> Cell | None:
        value = self.get(key, list, None, required)
        if value is None:
            return None
        if len(value) != 2 or not all(isinstance(v, int) and not isinstance(v, bool)
                                      for v in value):
            raise ScenarioError(self.source, self._fld(key), f"expected [x, y] integers, got "
                                f"{value!r}", "write the cell as e.g. [5, 5]")
        return int(value[0]), int(value[1])

    def finish(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise ScenarioError(self.source, self._fld(unknown[0]), "unknown key",
                                f"remove it; allowed here: {', '.join(sorted(self.used))}")


def _float_pair(value: Any, source: str, fld: str) -> tuple[float, float]:
    if not (isinstance(value, list) and len(value) == 2
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)):
        raise ScenarioError(source, fld, f"expected [x, y] in metres, got {value!r}",
                            "write a point as [x, y]")
    return float(value[0]), float(value[1])


def _dataclass_from_table(cls: type, tbl: _Table) -> Any:
    kwargs = {}
    for name, f in cls.__dataclass_fields__.items():
        value = tbl.get(name, float, None)
        if value is not None:
            kwargs[name] = value
        del f
    tbl.finish()
    return cls(**kwargs)


def parse_scenario(data: dict[str, Any], source: str, base_dir: Path) -> Scenario:
    """Build and validate a Scenario from parsed TOML (see scenarios/builtin/paper-50.toml)."""
    top = _Table(data, "", source)
    name = top.get("name", str, Path(source).stem)
    description = top.get("description", str, "")
    steps = top.get("steps_per_episode", int, 600)
    start, goal = top.cell("start"), top.cell("goal")

    arena = top.table("arena")
    cell_size = arena.get("cell_size_m", float, 1.0)
    map_file = arena.get("map", str, None)
    width, height = arena.get("width_m", float, None), arena.get("height_m", float, None)
    blocked_cells: tuple[Cell, ...] = ()
    if map_file is not None:
        grid_map = load_map(base_dir / map_file)
        mw, mh = grid_map.width * cell_size, grid_map.height * cell_size
        for given, derived, fld in ((width, mw, "width_m"), (height, mh, "height_m")):
            if given is not None and abs(given - derived) > 1e-9:
                raise ScenarioError(source, f"arena.{fld}", f"{given} m disagrees with the "
                                    f"map ({derived} m)", f"remove arena.{fld}: the map sets it")
        width, height = mw, mh
        blocked_cells = _blocked_cells(grid_map)
    elif width is None or height is None:
        raise ScenarioError(source, "arena.width_m" if width is None else "arena.height_m",
                            "is missing", "give width_m and height_m, or a map file")
    arena.finish()

    robot = _dataclass_from_table(Robot, top.table("robot"))
    rewards = _dataclass_from_table(Rewards, top.table("rewards"))

    obs = top.table("obstacles")
    circles: list[Circle] = []
    for i, item in enumerate(obs.get("circles", list, [])):
        fld = f"obstacles.circles[{i}]"
        if not (isinstance(item, list) and len(item) == 3 and all(
                isinstance(v, int | float) and not isinstance(v, bool) for v in item)):
            raise ScenarioError(source, fld, f"expected [x, y, radius] in metres, got {item!r}",
                                "write each circle as [x, y, r]")
        circles.append(Circle(float(item[0]), float(item[1]), float(item[2])))
    for i, raw in enumerate(obs.get("chains", list, [])):
        ch = _Table(raw, f"obstacles.chains[{i}]", source)
        p0 = _float_pair(ch.get("from", list, required=True), source, ch._fld("from"))
        p1 = _float_pair(ch.get("to", list, required=True), source, ch._fld("to"))
        radius = ch.get("radius_m", float, required=True)
        spacing = ch.get("spacing_m", float, 1.0)
        ch.finish()
        _finite_positive(radius, source, ch._fld("radius_m"), "use e.g. 0.6")
        _finite_positive(spacing, source, ch._fld("spacing_m"), "use e.g. 1.0")
        circles.extend(chain(p0, p1, radius, spacing))
    rnd = obs.get("random", dict, None)
    obs.finish()
    top.finish()

    sc = Scenario(name=name, width_m=width, height_m=height, start=start, goal=goal,
                  cell_size_m=cell_size, obstacles=tuple(circles), blocked_cells=blocked_cells,
                  robot=robot, rewards=rewards, steps_per_episode=steps,
                  description=description, source=source)
    if rnd is not None:
        rt = _Table(rnd, "obstacles.random", source)
        count = rt.get("count", int, required=True)
        rmin = rt.get("radius_min_m", float, required=True)
        rmax = rt.get("radius_max_m", float, required=True)
        seed = rt.get("seed", int, required=True)
        rt.finish()
        if count < 0:
            raise ScenarioError(source, "obstacles.random.count", "must be >= 0", "use e.g. 20")
        _finite_positive(rmin, source, "obstacles.random.radius_min_m", "use e.g. 1.0")
        _finite_positive(rmax, source, "obstacles.random.radius_max_m", "use e.g. 2.5")
        if rmax < rmin:
            raise ScenarioError(source, "obstacles.random.radius_max_m", "is below radius_min_m",
                                "swap them")
        validate_shape(sc)
        sc = replace(sc, obstacles=sc.obstacles + random_circles(
            sc, count, rmin, rmax, np.random.default_rng(seed)))
    validate(sc)
    return sc


def _blocked_cells(grid_map: GridMap) -> tuple[Cell, ...]:
    iy, ix = np.nonzero(grid_map.blocked)
    return tuple(zip(ix.tolist(), iy.tolist(), strict=True))


def load_scenario(path: str | Path) -> Scenario:
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ScenarioError(str(path), "file", "does not exist", "check the path") from None
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(str(path), "TOML", f"cannot be parsed ({exc})",
                            "fix the TOML syntax") from None
    return parse_scenario(data, str(path), path.parent)


def scenario_from_map(path: str | Path, start_xy: Cell, goal_xy: Cell,
                      cell_size_m: float = 1.0) -> Scenario:
    """A scenario from a bare ``.map``; start/goal in the Moving AI frame (y down)."""
    grid_map = load_map(path)
    h = grid_map.height
    sc = Scenario(name=Path(path).stem, width_m=grid_map.width * cell_size_m,
                  height_m=h * cell_size_m, start=movingai_to_cell(*start_xy, h),
                  goal=movingai_to_cell(*goal_xy, h), cell_size_m=cell_size_m,
                  blocked_cells=_blocked_cells(grid_map), source=str(path))
    validate(sc, names={"start": f"--start {start_xy[0]},{start_xy[1]}",
                        "goal": f"--goal {goal_xy[0]},{goal_xy[1]}"})
    return sc


def builtin_dir() -> Path:
    """Directory of the built-in scenario TOMLs, shipped as data in ``scenarios/builtin``.

    Found by path beside this package (installed or editable alike), so ``sim``
    reads the data without importing any code of the layer above it.
    """
    return Path(__file__).resolve().parent.parent / "scenarios" / "builtin"


def builtin_names() -> list[str]:
    return sorted(p.stem for p in builtin_dir().glob("*.toml"))


def resolve_scenario(spec: str, start: Cell | None = None, goal: Cell | None = None) -> Scenario:
    """A built-in name, a ``.toml`` path, or a ``.map`` path with start/goal (Moving AI frame)."""
    if spec.endswith(".map"):
        if start is None or goal is None:
            raise ScenarioError(spec, "--start/--goal", "a .map needs a start and a goal",
                                "pass --start X,Y --goal X,Y (Moving AI frame: y counts down)")
        return scenario_from_map(spec, start, goal)
    if start is not None or goal is not None:
        raise ScenarioError(spec, "--start/--goal", "only apply to a .map file",
                            "set start and goal inside the scenario TOML instead")
    if spec.endswith(".toml") or "/" in spec:
        return load_scenario(spec)
    path = builtin_dir() / f"{spec}.toml"
    if not path.is_file():
        raise ScenarioError(spec, "scenario", "is not a built-in scenario, .toml or .map",
                            f"use one of: {', '.join(builtin_names())}")
    return load_scenario(path)
