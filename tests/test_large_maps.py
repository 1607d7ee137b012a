"""Seeded large maps: deterministic, one connected free space, the kinds they claim."""

from __future__ import annotations

import numpy as np
import pytest

from sim.grid.planning import grid_distances
from sim.map_generators import GENERATORS, generate


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
    from scenarios.experiments.scaling_maps import main

    out = tmp_path / "sm"
    assert main(["--out", str(out), "--sizes", "32,48", "--kinds", "rooms", "--methods",
                 "rnh-ql+", "--seeds", "1", "--rewards", "goal-only", "--jobs", "1"]) == 0
    text = (out / "scaling-maps.md").read_text()
    assert "| rnh-ql+ | 1/1 ·" in text or "| rnh-ql+ | 0/1 ·" in text
    toml = (out / "maps" / "rooms-48.toml").read_text()
    assert "s_start_share = 0.1" in toml

    from scenarios.experiments.scaling_maps_figure import main as figure

    png = tmp_path / "fig" / "scaling.png"
    assert figure([str(out), "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000
    table = png.with_suffix(".md").read_text()
    assert "| rnh-ql+ | rooms |" in table and "32²" in table and "48²" in table


def test_the_figure_names_a_folder_that_is_not_a_study(tmp_path, capsys):
    from scenarios.experiments.scaling_maps_figure import main as figure

    assert figure([str(tmp_path), "--out", str(tmp_path / "x.png")]) == 2
    assert "scaling_maps" in capsys.readouterr().err
