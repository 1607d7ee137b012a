"""Seeded large maps: deterministic, one connected free space, the kinds they claim."""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid.planning import grid_distances
from sim.maps.generators import GENERATORS, generate


@pytest.mark.parametrize("kind", [k for k in GENERATORS if k != "city"])
def test_generated_maps_are_seeded_and_connected(kind):
    a = generate(kind, 96, 3)
    assert a.shape == (96, 96) and a.dtype == bool
    assert np.array_equal(a, generate(kind, 96, 3))
    assert not np.array_equal(a, generate(kind, 96, 4))
    r, c = np.argwhere(a)[0]
    reach = grid_distances(a, (int(c), int(r))) >= 0
    assert np.array_equal(reach, a)  # every free cell reaches every other
    assert 0.3 < a.mean() < 0.95


def _wall_segments(free, corridor):
    """The maze's structure read back from the map: every lattice cell free, every wall
    junction blocked, and each wall segment between two lattice cells all free (a gap
    exactly ``corridor`` cells wide) or all blocked. Returns the number of gaps."""
    pitch = corridor + 1
    n = (free.shape[0] - 1) // pitch
    inner = np.zeros_like(free)
    inner[1:n * pitch, 1:n * pitch] = True
    assert not (free & ~inner).any()  # nothing free beyond the lattice
    on_wall = (np.arange(free.shape[0]) % pitch) == 0
    assert free[np.outer(~on_wall, ~on_wall) & inner].all()  # every lattice cell free
    assert not free[np.ix_(on_wall, on_wall)].any()  # wall junctions blocked
    gaps = 0
    for t in (free, free.T):
        for k in range(1, n):
            for j in range(n):
                seg = t[k * pitch, j * pitch + 1:j * pitch + 1 + corridor]
                assert seg.all() or not seg.any(), (k, j, seg)
                gaps += int(seg.all())
    return gaps


@pytest.mark.parametrize("corridor", [1, 2, 4, 8])
def test_maze_corridors_are_as_wide_as_asked(corridor):
    """Moving AI's maze kind (braid 0): corridors and gaps exactly ``corridor`` cells wide,
    1-cell walls, a perfect maze (a spanning tree: n*n - 1 gaps, one route between any two
    cells); with braid, more gaps, still exactly as wide. Seeded and connected."""
    size = 64
    n = (size - 1) // (corridor + 1)
    perfect = generate("maze", size, 5, corridor=corridor, braid=0.0)
    assert np.array_equal(perfect, generate("maze", size, 5, corridor=corridor, braid=0.0))
    assert not np.array_equal(perfect, generate("maze", size, 6, corridor=corridor, braid=0.0))
    assert _wall_segments(perfect, corridor) == n * n - 1
    braided = generate("maze", size, 5, corridor=corridor, braid=0.2)
    assert _wall_segments(braided, corridor) > n * n - 1
    for free in (perfect, braided):
        r, c = np.argwhere(free)[0]
        assert np.array_equal(grid_distances(free, (int(c), int(r))) >= 0, free)


def test_maze_refuses_widths_that_do_not_fit():
    with pytest.raises(ValueError, match="corridor"):
        generate("maze", 64, 0, corridor=0)
    with pytest.raises(ValueError, match="lattice"):
        generate("maze", 16, 0, corridor=8)


def test_city_is_berlin_and_scales_by_whole_cells():
    small = generate("city", 256, 0)
    big = generate("city", 512, 0)
    assert big.shape == (512, 512) and np.array_equal(big[::2, ::2], small)
    with pytest.raises(ValueError, match="multiples of 256"):
        generate("city", 300, 0)


def test_unknown_kind_names_the_kinds():
    with pytest.raises(ValueError, match="city, maze"):
        generate("forest", 64, 0)


def test_the_study_runs_and_writes_its_table(tmp_path):
    from scenarios.studies.maps.scaling_maps import main

    out = tmp_path / "sm"
    assert main(["--out", str(out), "--sizes", "32,48", "--kinds", "rooms", "--methods",
                 "rnh-ql+", "--seeds", "1", "--rewards", "goal-only", "--jobs", "1"]) == 0
    text = (out / "scaling-maps.md").read_text()
    assert "| rnh-ql+ | 1/1 ·" in text or "| rnh-ql+ | 0/1 ·" in text
    toml = (out / "maps" / "rooms-48.toml").read_text()
    assert "s_start_share = 0.1" in toml

    from scenarios.studies.maps.scaling_maps_figure import main as figure

    png = tmp_path / "fig" / "scaling.png"
    assert figure([str(out), "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000
    table = png.with_suffix(".md").read_text()
    assert "| rnh-ql+ | rooms |" in table and "32²" in table and "48²" in table


def test_the_figure_names_a_folder_that_is_not_a_study(tmp_path, capsys):
    from scenarios.studies.maps.scaling_maps_figure import main as figure

    assert figure([str(tmp_path), "--out", str(tmp_path / "x.png")]) == 2
    assert "scaling_maps" in capsys.readouterr().err


def test_open_ground_blocks_a_tenth_of_the_cells():
    free = generate("open", 256, 11)
    assert 0.88 < free.mean() < 0.91  # 10 % blocked, a few free islands cut off
    assert np.array_equal(free, generate("random", 256, 11, density=0.1))


def test_streets_cut_blocks_of_bounded_size_by_straight_streets():
    """Every block is a rectangle of 6-24 cells a side between streets 2-10 wide: a row of
    the map meets runs of built cells no longer than 24 (nor shorter than 6 unless cut by
    the map's edge or an open square), and the map has streets crossing it end to end."""
    free = generate("streets", 256, 5)
    for line in (free, free.T):
        for row in line[::17]:
            runs = np.diff(np.flatnonzero(np.diff(np.r_[1, row.astype(int), 1])))[::2]
            assert runs.size == 0 or runs.max() <= 24
    crossing = [free[:, j].all() for j in range(256)] + [free[i, :].all() for i in range(256)]
    assert any(crossing)


def test_corner_placement_by_hand():
    from sim.grid.planning import corner_start_goal

    free = np.ones((5, 6), dtype=bool)
    free[0, 0] = False  # the corner blocked: S is the next cell of least row + col, the upper
    free[4, 5] = free[4, 4] = False  # G: most row + col among what S reaches, the lower
    free[1:4, 3] = False
    s, g, moves = corner_start_goal(free)
    assert s == (0, 1) and g == (3, 5)
    assert moves == grid_distances(free, (1, 0))[3, 5] == 7
