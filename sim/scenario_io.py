"""Loading scenarios: TOML files, Moving AI ``.map`` files and the built-ins by name.

Every error names the file, the field and the fix (:class:`sim.errors.ScenarioError`).
The built-in scenarios are ``sim``'s own package data, in ``sim/builtin``.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from sim.errors import ScenarioError
from sim.feasibility import validate
from sim.files import read_input
from sim.maps.layouts import chain, random_circles
from sim.maps.movingai import GridMap, load_map, movingai_to_cell
from sim.scenario import (
    MAX_COORDINATE_M,
    MAX_OBSTACLES,
    Cell,
    Circle,
    Rewards,
    Robot,
    Scenario,
    finite_positive,
    validate_shape,
)


class _Table:
    """A TOML table that remembers which keys were read, to reject unknown ones."""

    def __init__(self, data: dict[str, Any], path: str, source: str) -> None:
        if not isinstance(data, dict):
            raise ScenarioError(source, path or "<top>", f"expected a table, got {data!r}",
                                "see sim/builtin/paper-50.toml for the layout")
        self.data, self.path, self.source, self.used = data, path, source, set()

    def _fld(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def get(self, key: str, kind: type | tuple[type, ...], default: Any = None,
            required: bool = False) -> Any:
        self.used.add(key)
        if key not in self.data:
            if required:
                raise ScenarioError(self.source, self._fld(key), "is missing",
                                    f"add '{key} = ...' (see sim/builtin/paper-50.toml)")
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


def _rewards_from_table(tbl: _Table, source: str) -> Rewards:
    """``[rewards]``: ``scheme = "goal-only"`` picks a preset, ``goal/bump/step`` override it."""
    scheme = tbl.get("scheme", str, None)
    base = Rewards.preset(scheme, source, "rewards.scheme") if scheme is not None else Rewards()
    values = {k: tbl.get(k, float, None) for k in ("goal", "bump", "step")}
    tbl.finish()
    return replace(base, **{k: v for k, v in values.items() if v is not None}).named()


def _physics_from_table(table: dict | None, source: str) -> str | None:
    """``[physics]``: ``fidelity = "noisy"`` and/or knobs, as a ``--fidelity`` text (checked
    now, so a bad value names this file); None when absent."""
    if table is None:
        return None
    from sim.physics.fidelity import fidelity_from_table

    fidelity_from_table(table, source)  # validate
    items = dict(table)
    head = [str(items.pop("fidelity"))] if "fidelity" in items else []
    return ",".join(head + [f"{k}={str(v).lower() if isinstance(v, bool) else v}"
                            for k, v in items.items()])


def parse_scenario(data: dict[str, Any], source: str, base_dir: Path) -> Scenario:
    """Build and validate a Scenario from parsed TOML (see sim/builtin/paper-50.toml)."""
    top = _Table(data, "", source)
    name = top.get("name", str, Path(source).stem)
    description = top.get("description", str, "")
    steps = top.get("steps_per_episode", int, 600)
    s_share = top.get("s_start_share", (int, float), 0.0)
    start, goal = top.cell("start"), top.cell("goal")

    arena = top.table("arena")
    cell_size = arena.get("cell_size_m", float, 1.0)
    map_file = arena.get("map", str, None)
    width, height = arena.get("width_m", float, None), arena.get("height_m", float, None)
    blocked_cells: tuple[Cell, ...] = ()
    if map_file is not None:
        where = base_dir / map_file
        if not where.is_file():  # name the scenario and its field, not only the map's path
            what = "is a folder" if where.exists() else "does not exist"
            raise ScenarioError(source, "arena.map", f"{map_file!r} is not a file ({where} "
                                f"{what})", "give the .map's path relative to the scenario "
                                "file")
        grid_map = load_map(where)
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
    rewards = _rewards_from_table(top.table("rewards"), source)
    physics = _physics_from_table(top.get("physics", dict, None), source)

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
        finite_positive(radius, source, ch._fld("radius_m"), "use e.g. 0.6")
        finite_positive(spacing, source, ch._fld("spacing_m"), "use e.g. 1.0")
        for point, end in ((p0, "from"), (p1, "to")):
            if not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE_M for v in point):
                raise ScenarioError(source, ch._fld(end), f"{list(point)} is beyond "
                                    f"{MAX_COORDINATE_M:g} m", "give the point in the arena")
        posts = math.hypot(p1[0] - p0[0], p1[1] - p0[1]) / spacing
        if posts > MAX_OBSTACLES - len(circles):
            raise ScenarioError(source, ch._fld("spacing_m"), f"{spacing:g} m makes "
                                f"{posts:,.0f} circles, more than the limit {MAX_OBSTACLES:,}",
                                "use a larger spacing (e.g. 1.0)")
        circles.extend(chain(p0, p1, radius, spacing))
    rnd = obs.get("random", dict, None)
    obs.finish()
    top.finish()

    sc = Scenario(name=name, width_m=width, height_m=height, start=start, goal=goal,
                  cell_size_m=cell_size, obstacles=tuple(circles), blocked_cells=blocked_cells,
                  robot=robot, rewards=rewards, steps_per_episode=steps, physics=physics,
                  s_start_share=float(s_share),
                  description=description, source=source)
    if rnd is not None:
        rt = _Table(rnd, "obstacles.random", source)
        count = rt.get("count", int, required=True)
        rmin = rt.get("radius_min_m", float, required=True)
        rmax = rt.get("radius_max_m", float, required=True)
        seed = rt.get("seed", int, required=True)
        rt.finish()
        if not 0 <= seed < 2**64:
            raise ScenarioError(source, "obstacles.random.seed", f"must be in 0..2^64-1, got "
                                f"{seed}", "use e.g. 50")
        if count < 0:
            raise ScenarioError(source, "obstacles.random.count", "must be >= 0", "use e.g. 20")
        if count > MAX_OBSTACLES:
            raise ScenarioError(source, "obstacles.random.count", f"{count:,} is more than the "
                                f"limit {MAX_OBSTACLES:,}", "use fewer circles")
        validate_shape(sc)  # the arena's size first: drawing circles in a huge one takes ages
        if count > sc.nx * sc.ny:
            raise ScenarioError(source, "obstacles.random.count", f"{count:,} circles in "
                                f"{sc.nx * sc.ny:,} cells cannot leave a route",
                                "use fewer circles")
        validate(sc)  # S, G and their connection with the fixed obstacles alone, named as such
        finite_positive(rmin, source, "obstacles.random.radius_min_m", "use e.g. 1.0")
        finite_positive(rmax, source, "obstacles.random.radius_max_m", "use e.g. 2.5")
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
    raw = read_input(path, ScenarioError, "a scenario file", "pass a .toml or .map file inside it")
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(str(path), "TOML", f"cannot be parsed ({exc})",
                            "fix the TOML syntax") from None
    except RecursionError:  # tables or arrays nested thousands deep
        raise ScenarioError(str(path), "TOML", "is nested too deeply to parse",
                            "a scenario nests tables two levels deep: see "
                            "sim/builtin/paper-50.toml") from None
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
    """Directory of the built-in scenario TOMLs and their maps: the package data
    ``sim/builtin`` (``pyproject.toml`` ships it; tests check every file is shipped)."""
    return Path(__file__).resolve().parent / "builtin"


SCENARIO_PATH_ENV = "RNHQL_SCENARIO_PATH"


def scenario_dirs() -> list[Path]:
    """Where a scenario name is looked up, in order: the folders of ``$RNHQL_SCENARIO_PATH``
    (separated by ``os.pathsep``; a user's own ``NAME.toml`` files), then the built-ins."""
    extra = [Path(p).expanduser() for p in os.environ.get(SCENARIO_PATH_ENV, "").split(os.pathsep)
             if p.strip()]
    for folder in extra:
        if not folder.is_dir():
            raise ScenarioError(f"${SCENARIO_PATH_ENV}", str(folder),
                                "is not a folder" if folder.exists() else "no such folder",
                                f"point {SCENARIO_PATH_ENV} at folders of NAME.toml files "
                                f"(separated by '{os.pathsep}'), or unset it")
    return [*extra, builtin_dir()]


def builtin_names() -> list[str]:
    """Every scenario that can be named: the built-ins and those of ``$RNHQL_SCENARIO_PATH``."""
    return sorted({p.stem for d in scenario_dirs() for p in d.glob("*.toml")})


def named_scenario_path(name: str) -> Path | None:
    for d in scenario_dirs():
        path = d / f"{name}.toml"
        if path.is_file():
            return path
    return None


def resolve_scenario(spec: str | Path | Scenario, start: Cell | None = None,
                     goal: Cell | None = None) -> Scenario:
    """A built-in name, a ``.toml`` path, a ``.map`` path with start/goal (Moving AI frame), or a
    :class:`Scenario` built in Python (checked as a file's would be)."""
    if isinstance(spec, Scenario):
        if start is not None or goal is not None:
            raise ScenarioError(spec.source, "start/goal", "only apply to a .map file",
                                "set start and goal in the Scenario (dataclasses.replace)")
        validate_shape(spec)
        validate(spec)
        return spec
    if isinstance(spec, Path):
        spec = str(spec)
    if not isinstance(spec, str):
        raise ScenarioError("<python>", "scenario", f"is a {type(spec).__name__}, not a "
                            "scenario", "pass a built-in name, a .toml or .map path, or a "
                            "sim.scenario.Scenario")
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
    path = named_scenario_path(spec)
    if path is None:
        raise ScenarioError(spec, "scenario", "is not a named scenario, .toml or .map",
                            f"use one of: {', '.join(builtin_names())} (`rnhql scenarios` "
                            f"lists them; ${SCENARIO_PATH_ENV} adds folders of your own)")
    sc = load_scenario(path)
    if sc.name != spec:  # a copy saved under a new file name: it would run, list and record
        # as the scenario it was copied from
        raise ScenarioError(str(path), "name", f"is {sc.name!r}, but the file is named "
                            f"{spec!r}, so `{spec}` would run as {sc.name!r}",
                            f'set name = "{spec}" in the file (or name the file '
                            f'{sc.name}.toml)')
    return sc
