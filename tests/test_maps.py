from __future__ import annotations

import pytest

from sim.errors import MapError
from sim.maps.movingai import cell_to_movingai, load_map, load_scen, movingai_to_cell, parse_map
from tests.conftest import MAPS

GOOD = "type octile\nheight 2\nwidth 3\nmap\n.@.\n..T\n"


def test_parse_map_flips_rows_into_the_y_up_frame():
    m = parse_map(GOOD, "x.map")
    # Moving AI row 0 ('.@.') is the top, i.e. rnhql row iy = 1
    assert m.blocked.tolist() == [[False, False, True], [False, True, False]]
    assert movingai_to_cell(1, 0, 2) == (1, 1)
    assert cell_to_movingai(*movingai_to_cell(2, 1, 2), 2) == (2, 1)


def test_arena_map_and_scen_load():
    m = load_map(MAPS / "arena.map")
    assert (m.width, m.height) == (49, 49)
    problems = load_scen(MAPS / "arena.map.scen")
    assert len(problems) == 130


@pytest.mark.parametrize(("text", "field", "words"), [
    ("type octile\nheigth 2\nwidth 3\nmap\n...\n...\n", "header line 2", "expected 'height"),
    ("type octile\nheight 2\nwidth 3\nmap\n...\n..\n", "line 6", "2 characters"),
    ("type octile\nheight 2\nwidth 3\nmap\n...\n.x.\n", "line 6, column 2",
     "unknown map character"),
    ("type octile\nheight 3\nwidth 3\nmap\n...\n...\n", "rows", "height 3 but 2 rows"),
    ("hello\n", "header line 1", "type octile"),
    ("type octile\nheight -1\nwidth 3\nmap\n", "header line 2", "positive"),
])
def test_bad_maps_name_line_and_fix(text, field, words):
    with pytest.raises(MapError) as info:
        parse_map(text, "bad.map")
    err = info.value
    assert err.field == field
    assert words in str(err)
    assert str(err).startswith("bad.map: ") and "Fix: " in str(err)


def test_unsupported_map_type_and_scen_version_are_refused(tmp_path):
    from sim.errors import InputError
    from sim.maps.movingai import load_scen, parse_map

    with pytest.raises(InputError, match="'hexagonal' is not supported"):
        parse_map("type hexagonal\nheight 1\nwidth 1\nmap\n.\n", "h.map")
    scen = tmp_path / "v.scen"
    scen.write_text("version 99\n")
    with pytest.raises(MapError, match="'version 99' is not supported"):
        load_scen(scen)
