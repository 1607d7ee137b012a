"""What a recording shows by default, read back from the file or from its blueprint:
labels off the map's obstacles, a key for the comparison's lines and colours, titles that
fit, legends off the curves, the potential named by the method, readable policy arrows,
the physics timeline note, and recording properties to filter a folder by."""

from __future__ import annotations

import uuid

import numpy as np
import pytest
import rerun as rr
import rerun.blueprint as rrb

from learning.methods.registry import comparison_methods
from scenarios.palette import method_colour
from scenarios.recording import blueprint, scene
from scenarios.recording.comparison import gather_comparison
from scenarios.recording.demo import record_synthetic
from scenarios.recording.recorder import policy_arrow_cells, run_prefix
from scenarios.recording.summary import summary_curves
from tests.test_recording import _comparison_parts, _views, read_table


def rgb(packed: int) -> tuple[int, int, int]:
    """Rerun's colours are 0xRRGGBBAA."""
    return (packed >> 24) & 255, (packed >> 16) & 255, (packed >> 8) & 255


def static_column(path, entity: str, column: str) -> list:
    table = read_table(path, [entity], None)
    return table.column(f"{entity}:{column}").to_pylist()[0]


def property_columns(path) -> dict:
    """Every property column of the recording's row in the catalog (``property:NAME:FIELD``),
    as a viewer or a script filtering a folder of recordings sees them."""
    pytest.importorskip("datafusion")
    with rr.server.Server(host="127.0.0.1", datasets={"d": [str(path)]}) as server:
        client = server.client()
        row = client.get_dataset("d").segment_table().to_pandas().iloc[0]
    return {k: v[0] for k, v in row.items() if k.startswith("property:")}


def properties(path) -> dict:
    """The recording's ``rnhql`` properties by field."""
    return {k.split(":", 2)[2]: v for k, v in property_columns(path).items()
            if k.startswith("property:rnhql:")}


@pytest.fixture(scope="module")
def plus_run(tmp_path_factory, paper50, paper50_model):
    path = tmp_path_factory.mktemp("views") / "plus.rrd"
    record_synthetic(path, paper50, paper50_model, episodes=20, record_every=10,
                     values_every=10, method="rnh-ql+")
    return path


@pytest.fixture(scope="module")
def physics_run(tmp_path_factory, paper50, paper50_model):
    path = tmp_path_factory.mktemp("views") / "physics.rrd"
    record_synthetic(path, paper50, paper50_model, episodes=10, record_every=5,
                     values_every=5, method="rnh-ql", world="physics", fidelity="noisy")
    return path


@pytest.fixture(scope="module")
def comparison(tmp_path_factory, paper50, paper50_model):
    tmp = tmp_path_factory.mktemp("views")
    rid = str(uuid.uuid4())
    runs = [("rnh-ql", 0), ("st-ql", 0)]
    parts = _comparison_parts(tmp, paper50, paper50_model, runs, rid)
    records = [{"key": m, "steps_per_episode": [5] * 20, "return_per_episode": [1.0] * 20,
                "success_per_episode": [1] * 20} for m, _ in runs]
    curves = summary_curves(records, lambda r: r["key"])
    return gather_comparison(tmp / "c.rrd", parts, paper50, runs, recording_id=rid,
                             curves=curves), runs


# ---------------------------------------------------------------- (a) labels and the key


def test_route_label_sits_under_the_arena_off_every_obstacle(plus_run, paper50):
    ent = f"/world/routes/{rr.escape_entity_path_part('final route')}/label"
    (x, y), = static_column(plus_run, ent, "Points2D:positions")
    assert y < 0 and x == paper50.width_m / 2  # under the arena (y up), centred
    for o in paper50.obstacles:
        assert np.hypot(x - o.x_m, y - o.y_m) > o.radius_m + 1.0


def test_comparison_key_names_the_map_lines_and_every_method_in_its_colour(comparison):
    path, runs = comparison
    labels = static_column(path, "/key", "Points2D:labels")
    colours = [rgb(c) for c in static_column(path, "/key", "Points2D:colors")]
    shown = dict(zip(labels, colours, strict=True))
    assert shown["BFS shortest route"] == scene.BFS_ROUTE
    assert shown["final greedy route"] == scene.ROUTE_PALETTE[0]
    assert shown["last training episode"] == scene.TRAIN
    assert shown["greedy test from S"] == scene.GREEDY
    for method, _ in runs:
        assert shown[method] == method_colour(method)


def test_comparison_layout_has_a_key_panel_and_no_legend_over_a_plot(paper50):
    runs = [(m, s) for m in ("rnh-ql", "st-ql") for s in range(2)]
    key = ((-5, 5), (0, 12))
    views = _views(blueprint.comparison_blueprint(runs, paper50, run_prefix, key=key))
    assert [v for v in views if v.name == "Key" and str(v.origin) == "/key"]
    plots = [v for v in views if isinstance(v, rrb.TimeSeriesView)]
    assert len(plots) == 4  # the greedy test from S, steps, success, reward per step
    for v in plots:
        assert v.properties["PlotLegend"].visible.as_arrow_array().to_pylist() == [False]


# ---------------------------------------------------------------- (b) titles that fit

# a third of a 1600-pixel window, less the panel's buttons, holds ~36 characters of title
THIRD, HALF_OF_RIGHT = 36, 36


def test_comparison_titles_show_whole(paper50):
    runs = [(m, 0) for m in comparison_methods()]
    for v in _views(blueprint.comparison_blueprint(runs, paper50, run_prefix,
                                                      ((-5, 5), (0, 12)))):
        assert len(v.name) <= THIRD, v.name


def test_single_run_titles_show_whole(paper50):
    bp = blueprint.run_blueprint("", paper50, "rnh-ql+ablation", "physics", "noisy")
    for v in _views(bp):
        limit = 80 if v.name.startswith(("Map", "Training steps")) else HALF_OF_RIGHT
        assert len(v.name) <= limit, v.name


# ---------------------------------------------------------------- (c) the method colours


def test_summary_curves_are_drawn_in_the_palette_colours(comparison):
    path, runs = comparison
    for method, _ in runs:
        ent = f"/summary/steps/{rr.escape_entity_path_part(method)}"
        colour = static_column(path, ent, "SeriesLines:colors")[0]
        assert rgb(colour) == method_colour(method)


# ---------------------------------------------------------------- (d) the potential's name


@pytest.mark.parametrize(("method", "name"), [("rnh-ql+", "Φ"), ("rnh-ql", "V_NN")])
def test_the_potential_is_named_by_what_the_method_shapes_with(tmp_path, paper50,
                                                               paper50_model, method, name):
    path = tmp_path / "r.rrd"
    record_synthetic(path, paper50, paper50_model, episodes=10, record_every=5,
                     values_every=5, method=method)
    table = read_table(path, ["/world/values/v_nn/legend"], "episode")
    captions = [row[0] for row in table.column(
        "/world/values/v_nn/legend:Points2D:labels").to_pylist() if row]
    assert captions and all(c.startswith(f"{name}: ") for c in captions)
    assert blueprint.value_title(method).startswith(name)
    assert "V_NN" not in blueprint.value_title("rnh-ql+")


# ---------------------------------------------------------------- (e) policy arrows


def test_policy_arrows_are_a_readable_field(plus_run, paper50_model):
    m = paper50_model
    k, cells = policy_arrow_cells(m, np.flatnonzero(m.distance_to_goal > 0))
    assert k == 3  # 50 cells across: 17 arrows, each 3 cells apart
    table = read_table(plus_run, ["/world/values/policy"], "episode")
    vectors = np.array(table.column("/world/values/policy:Arrows2D:vectors").to_pylist()[0])
    assert len(vectors) == len(cells)
    lengths = np.hypot(vectors[:, 0], vectors[:, 1])
    np.testing.assert_allclose(lengths, 0.8 * k * m.cell_size_m, rtol=1e-5)
    radius = static_column(plus_run, "/world/values/policy", "Arrows2D:radii")[0]
    assert radius == pytest.approx(0.1 * k * m.cell_size_m)


# ---------------------------------------------------------------- (f) success legend


def test_single_run_plots_name_their_series_in_the_title_not_a_legend(paper50):
    plots = [v for v in _views(blueprint.run_blueprint("", paper50, "rnh-ql"))
             if isinstance(v, rrb.TimeSeriesView)]
    by_name = {v.name: v for v in plots}
    success = next(v for n, v in by_name.items() if n.startswith("Success rate"))
    assert success.properties["PlotLegend"].visible.as_arrow_array().to_pylist() == [False]
    (lo, hi), = success.properties["ScalarAxis"].range.as_arrow_array().to_pylist()
    assert lo < 0 and 1 < hi < 1.1  # the 0/1 dots and the rate fill the panel
    for v in plots:
        legend = v.properties["PlotLegend"].visible.as_arrow_array().to_pylist()
        assert legend == [v.name == "Shaping F"], v.name  # two series in a tab named Shaping F
    assert scene.SERIES_COLOURS["steps/optimal"] == scene.BFS_ROUTE  # "blue: the BFS optimum"
    assert "blue" in next(n for n in by_name if n.startswith("Training steps"))


# ---------------------------------------------------------------- (g) the sim_time note


def test_physics_run_tells_the_user_to_pick_sim_time(physics_run, paper50):
    note = static_column(physics_run, "/notes/drive", "TextDocument:text")[0]
    assert "sim_time" in note and "play" in note
    docs = [v for v in _views(blueprint.run_blueprint("", paper50, "rnh-ql", "physics"))
            if isinstance(v, rrb.TextDocumentView)]
    assert any(str(v.origin) == "/notes/drive" for v in docs)
    grid_docs = [v for v in _views(blueprint.run_blueprint("", paper50, "rnh-ql", "grid"))
                 if isinstance(v, rrb.TextDocumentView)]
    assert not any(str(v.origin) == "/notes/drive" for v in grid_docs)


# ---------------------------------------------------------------- (i) recording properties


def test_runs_carry_the_properties_a_folder_is_filtered_by(plus_run, physics_run):
    grid, phys = properties(plus_run), properties(physics_run)
    assert (grid["kind"], grid["method"], grid["seed"], grid["world"]) == (
        "run", "rnh-ql+", 0, "grid")
    assert grid["fidelity"] == "none (grid)" and grid["rewards"] == "paper"
    assert grid["version"] == scene.versions()["rnhql"] and grid["scenario"] == "paper-50"
    assert (phys["world"], phys["fidelity"]) == ("physics", "noisy")


def test_a_comparison_carries_what_it_compares(comparison):
    path, _ = comparison
    props = properties(path)
    assert props["kind"] == "comparison" and props["methods"] == "rnh-ql, st-ql"
    assert props["scenario"] == "paper-50" and props["seeds"] == 1 and props["runs"] == 2
    # its runs' own properties stay out of the catalog row (their card is their meta)
    assert not [k for k in property_columns(path) if "runs/" in k]
