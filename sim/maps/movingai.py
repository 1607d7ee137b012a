"""Moving AI benchmark maps (``.map``) and scenario lists (``.scen``).

Frame: Moving AI puts (0, 0) at the top-left cell, x to the right and y (the row)
growing *downwards*. rnhql's frame has y growing upwards, so a map row ``r``
becomes grid row ``iy = height - 1 - r``. :func:`movingai_to_cell` is the one
place that conversion happens.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sim.errors import MapError
from sim.files import read_input
from sim.scenario import MAX_CELLS_PER_SIDE

PASSABLE = frozenset(".GS")
BLOCKED = frozenset("@OTW")


@dataclass(frozen=True)
class GridMap:
    """A passability map in rnhql's frame: ``blocked[iy, ix]``, row 0 at the bottom."""

    blocked: np.ndarray  # bool[height, width]
    source: str

    @property
    def width(self) -> int:
        return int(self.blocked.shape[1])

    @property
    def height(self) -> int:
        return int(self.blocked.shape[0])


@dataclass(frozen=True)
class ScenProblem:
    """One line of a ``.scen`` file, coordinates still in the Moving AI frame."""

    bucket: int
    map_name: str
    width: int
    height: int
    start_xy: tuple[int, int]
    goal_xy: tuple[int, int]
    optimal_length: float


def movingai_to_cell(x: int, y: int, height: int) -> tuple[int, int]:
    """Moving AI (column, row-from-top) -> rnhql cell (ix, iy-from-bottom)."""
    return int(x), int(height - 1 - y)


def cell_to_movingai(ix: int, iy: int, height: int) -> tuple[int, int]:
    """rnhql cell (ix, iy-from-bottom) -> Moving AI (column, row-from-top)."""
    return int(ix), int(height - 1 - iy)


def _header_value(lines: list[str], index: int, key: str, source: str) -> int:
    field = f"header line {index + 1}"
    if index >= len(lines):
        raise MapError(source, field, f"missing '{key} N'", f"add a line '{key} N' to the header")
    parts = lines[index].split()
    if len(parts) != 2 or parts[0] != key:
        raise MapError(
            source, field, f"expected '{key} N', found {lines[index].strip()!r}",
            "use the Moving AI header: 'type octile', 'height H', 'width W', 'map'",
        )
    try:
        value = int(parts[1])
    except ValueError:
        raise MapError(source, field, f"{key} {parts[1]!r} is not an integer",
                       f"write the {key} as a positive integer") from None
    if value <= 0:
        raise MapError(source, field, f"{key} must be positive, got {value}",
                       f"write the {key} as a positive integer")
    if value > MAX_CELLS_PER_SIDE:
        raise MapError(source, field, f"{key} {value:,} is more than the limit of "
                       f"{MAX_CELLS_PER_SIDE} cells a side", "use a smaller map")
    return value


def parse_map(text: str, source: str) -> GridMap:
    """Parse the text of a ``.map`` file; errors name the line and the fix."""
    lines = text.splitlines()
    if not lines or lines[0].split()[:1] != ["type"]:
        raise MapError(source, "header line 1", "expected 'type octile'",
                       "start the file with the Moving AI header 'type octile'")
    if lines[0].split()[1:] != ["octile"]:
        raise MapError(source, "header line 1", f"map type {' '.join(lines[0].split()[1:])!r} "
                       "is not supported (only square grids: 'type octile')",
                       "use a Moving AI octile map")
    height = _header_value(lines, 1, "height", source)
    width = _header_value(lines, 2, "width", source)
    if len(lines) < 4 or lines[3].strip() != "map":
        raise MapError(source, "header line 4", "expected the line 'map'",
                       "put a line 'map' between the header and the rows")
    rows = [line.rstrip("\r\n") for line in lines[4:]]
    while rows and rows[-1].strip() == "":
        rows.pop()
    if len(rows) != height:
        raise MapError(source, "rows", f"header says height {height} but {len(rows)} rows follow",
                       "make the number of rows match 'height'")
    blocked = np.zeros((height, width), dtype=bool)
    for r, row in enumerate(rows):
        line_no = r + 5
        if len(row) != width:
            raise MapError(source, f"line {line_no}",
                           f"row has {len(row)} characters, header says width {width}",
                           "make every row exactly 'width' characters long")
        for c, ch in enumerate(row):
            if ch in BLOCKED:
                blocked[height - 1 - r, c] = True
            elif ch not in PASSABLE:
                raise MapError(source, f"line {line_no}, column {c + 1}",
                               f"unknown map character {ch!r}",
                               "use '.', 'G' or 'S' for free cells and '@', 'O', 'T' or 'W' "
                               "for blocked ones")
    return GridMap(blocked=blocked, source=source)


def load_map(path: str | Path) -> GridMap:
    path = Path(path)
    raw = read_input(path, MapError, "a map", "pass a Moving AI .map file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise MapError(str(path), "file", "is not a text file",
                       "pass a Moving AI .map text file") from None
    return parse_map(text, str(path))


def read_free_grid(path: str | Path) -> np.ndarray:
    """``free[row, col]`` of a ``.map`` file, row 0 at the top as in the file (the frame
    the map generators draw in, :mod:`sim.maps.generators`): :func:`load_map`, flipped
    back from rnhql's y-up frame and inverted to True = free."""
    return ~load_map(path).blocked[::-1]


def write_free_grid(free: np.ndarray, path: str | Path) -> None:
    """Write ``free[row, col]`` (row 0 at the top) as a Moving AI ``.map`` file, '.' free
    and '@' blocked, so a generated map is read back by :func:`load_map` like a
    downloaded one."""
    h, w = free.shape
    rows = ["".join("." if f else "@" for f in row) for row in free]
    Path(path).write_text(f"type octile\nheight {h}\nwidth {w}\nmap\n" + "\n".join(rows)
                          + "\n")


def load_scen(path: str | Path) -> list[ScenProblem]:
    """Read a ``.scen`` file (``version 1`` then tab-separated problems)."""
    path = Path(path)
    raw = read_input(path, MapError, "a .scen file", "pass a Moving AI .scen text file")
    try:
        lines = raw.decode("utf-8").splitlines()
    except UnicodeDecodeError:
        raise MapError(str(path), "file", "is not a text file",
                       "pass a Moving AI .scen text file") from None
    if not lines or not lines[0].startswith("version"):
        raise MapError(str(path), "line 1", "expected 'version 1'",
                       "start the file with the Moving AI line 'version 1'")
    if lines[0].split()[1:2] not in (["1"], ["1.0"]):
        raise MapError(str(path), "line 1", f"{lines[0].strip()!r} is not supported",
                       "use a Moving AI .scen file of 'version 1'")
    problems = []
    for i, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        parts = line.split("\t")
        if len(parts) != 9:
            raise MapError(str(path), f"line {i}", f"expected 9 tab-separated fields, got "
                           f"{len(parts)}", "use: bucket map width height sx sy gx gy length")
        try:
            problems.append(ScenProblem(
                bucket=int(parts[0]), map_name=parts[1], width=int(parts[2]),
                height=int(parts[3]), start_xy=(int(parts[4]), int(parts[5])),
                goal_xy=(int(parts[6]), int(parts[7])), optimal_length=float(parts[8])))
        except ValueError as exc:
            raise MapError(str(path), f"line {i}", f"bad number ({exc})",
                           "write integers for sizes and coordinates") from None
        q = problems[-1]
        if not (0 < q.width <= MAX_CELLS_PER_SIDE and 0 < q.height <= MAX_CELLS_PER_SIDE):
            raise MapError(str(path), f"line {i}", f"map size {q.width}x{q.height} is outside "
                           f"1..{MAX_CELLS_PER_SIDE} a side", "use the .scen of this map")
        if not all(0 <= v < lim for v, lim in ((q.start_xy[0], q.width), (q.start_xy[1], q.height),
                                               (q.goal_xy[0], q.width), (q.goal_xy[1], q.height))):
            raise MapError(str(path), f"line {i}", f"start {q.start_xy} or goal {q.goal_xy} is "
                           f"outside the {q.width}x{q.height} map", "use the .scen of this map")
        if not math.isfinite(q.optimal_length) or q.optimal_length < 0:
            raise MapError(str(path), f"line {i}", f"optimal length {q.optimal_length} is not "
                           "a finite length", "use the .scen of this map")
    return problems
