"""Rerun recordings: files verify, data round-trips, Ctrl-C leaves a good file, merging."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from scenarios.recording.batch import grid_poses
from scenarios.recording.comparison import gather_comparison
from scenarios.recording.demo import record_synthetic
from scenarios.recording.recorder import Recorder, RecordingFile, run_prefix, verify_recording
from scenarios.recording.scene import git_commit
from sim.grid.planning import bfs_route

REPO = Path(__file__).resolve().parent.parent


def read_table(path: Path, contents: list[str], index: str | None):
    """The recording as an Arrow table via the catalog API (needs rerun-sdk[catalog]).

    ``index=None`` reads the static data.
    """
    pytest.importorskip("datafusion")
    import rerun as rr

    with rr.server.Server(host="127.0.0.1", datasets={"d": [str(path)]}) as server:
        ds = server.client().get_dataset("d")
        return ds.filter_contents(contents).reader(index=index).to_arrow_table()


def positions(table, entity: str) -> np.ndarray:
    col = table.column(f"{entity}:Points2D:positions").to_pylist()
    return np.array([row[0] for row in col], dtype=np.float64)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory, paper50, paper50_model):
    path = tmp_path_factory.mktemp("rec") / "run.rrd"
    out = record_synthetic(path, paper50, paper50_model, episodes=40, record_every=10,
                           values_every=20)
    return path, out


def test_recording_verifies_and_part_is_renamed(synthetic):
    path, _ = synthetic
    ok, msg = verify_recording(path)
    assert ok, msg
    assert not path.with_name(path.name + ".part").exists()


def test_robot_positions_round_trip(synthetic, paper50_model):
    path, out = synthetic
    table = read_table(path, ["/world/robot"], "step")
    got = positions(table, "/world/robot")
    trajs = [out["trajectories"][k] for k in sorted(out["trajectories"])]
    want = np.concatenate([paper50_model.coords[s] for s in trajs])
    np.testing.assert_allclose(got, want, atol=1e-5)  # float32 in the file
    episodes = np.array(table.column("episode").to_pylist())
    np.testing.assert_array_equal(
        episodes, np.concatenate([np.full(len(out["trajectories"][k]), k)
                                  for k in sorted(out["trajectories"])]))
    np.testing.assert_array_equal(table.column("step").to_pylist(), np.arange(len(want)))


def test_metrics_round_trip(synthetic, paper50_model):
    path, _ = synthetic
    table = read_table(path, ["/metrics/steps/**"], "episode")
    assert table.num_rows == 40
    optimal = [v[0] for v in table.column("/metrics/steps/optimal:Scalars:scalars").to_pylist()
               if v is not None]  # a constant: logged at each batch's first and last episode
    assert len(optimal) >= 2 and set(optimal) == {paper50_model.optimal_route_length}
    heat = read_table(path, ["/world/values/max_q", "/world/values/policy"], "episode")
    assert heat.column("episode").to_pylist() == [19, 39]  # every 20 episodes
    arrows = heat.column("/world/values/policy:Arrows2D:vectors").to_pylist()
    from scenarios.recording.recorder import policy_arrow_cells

    reachable = np.flatnonzero(paper50_model.distance_to_goal > 0)
    assert len(arrows[0]) == len(policy_arrow_cells(paper50_model, reachable)[1])


def test_static_scene_has_bfs_route(synthetic, paper50_model):
    path, _ = synthetic
    table = read_table(path, ["/world/routes/bfs"], None)
    strip = table.column("/world/routes/bfs:LineStrips2D:strips").to_pylist()[0][0]
    m = paper50_model
    want = m.coords[bfs_route(m.next_state, m.distance_to_goal, m.start)]
    np.testing.assert_allclose(np.array(strip), want, atol=1e-5)


def test_physics_poses_sim_time_and_contacts(tmp_path, paper50, paper50_model):
    m = paper50_model
    path = tmp_path / "phys.rrd"
    states = np.array([m.start, m.start, m.next_state[m.start, 3], m.next_state[m.start, 3]])
    poses = np.column_stack([m.coords[states] + 0.1, [0.0, 0.5, 1.0, 1.5]])
    with Recorder.create(path, paper50, m, method="rnh-ql", config={"a": 1}, seed=3,
                         world="physics") as rec:
        for ep in range(2):
            rec.log_episode_trajectory(ep, states, poses=poses, sim_time_s=[0.0, 0.2, 0.4, 0.6],
                                       contacts=[[1.0, 2.0]], contact_steps=[1])
    assert verify_recording(path)[0]
    table = read_table(path, ["/world/robot"], "sim_time")
    np.testing.assert_allclose(positions(table, "/world/robot"),
                               np.concatenate([poses[:, :2]] * 2), atol=1e-5)
    t = np.array(table.column("sim_time").to_pylist(), dtype="timedelta64[ns]")
    np.testing.assert_allclose(t.astype(np.int64) / 1e9, [0, .2, .4, .6, .8, 1.0, 1.2, 1.4])
    events = read_table(path, ["/world/train/events"], "step")
    texts = [r[0] for r in events.column("/world/train/events:TextLog:text").to_pylist()]
    assert any("contact at (1.00, 2.00) m, step 1" in t for t in texts)


def test_physics_substeps_put_the_continuous_drive_on_sim_time(tmp_path, paper50,
                                                               paper50_model):
    """Between the states, every physics step's pose is on `sim_time` (same clock)."""
    m = paper50_model
    path = tmp_path / "sub.rrd"
    states = np.array([m.start, m.next_state[m.start, 3]])
    poses = np.column_stack([m.coords[states], [0.0, 0.0]])
    sub = np.column_stack([np.linspace(poses[0, 0], poses[1, 0], 5)[1:],
                           np.full(4, poses[0, 1]), np.zeros(4)])
    with Recorder.create(path, paper50, m, method="rnh-ql", config={}, seed=0,
                         world="physics") as rec:
        rec.log_episode_trajectory(0, states, poses=poses, sim_time_s=[0.0, 0.4],
                                   substeps=sub, substep_times_s=[0.1, 0.2, 0.3, 0.4])
    table = read_table(path, ["/world/robot"], "sim_time")
    t = np.array(table.column("sim_time").to_pylist(), dtype="timedelta64[ns]")
    np.testing.assert_allclose(t.astype(np.int64) / 1e9, [0.0, 0.1, 0.2, 0.3, 0.4])
    np.testing.assert_allclose(positions(table, "/world/robot")[1:, 0], sub[:, 0], atol=1e-5)


def test_grid_heading_follows_last_move(paper50_model):
    m = paper50_model
    s0 = m.start
    up, right = m.next_state[s0, 0], m.next_state[s0, 3]
    states = np.array([s0, s0, up, up, s0, s0, right])  # ep 1: [s0 s0 up up], ep 2: [s0 s0 right]
    _, vec = grid_poses(m, states, np.array([0, 4]))
    c = m.cell_size_m
    np.testing.assert_allclose(vec, [[0, c], [0, c], [0, c], [0, c], [c, 0], [c, 0], [c, 0]])


def test_close_is_idempotent_and_bad_input_is_rejected(tmp_path, paper50, paper50_model):
    rec = Recorder.create(tmp_path / "x.rrd", paper50, paper50_model, method="st-ql",
                          config={}, seed=0)
    with pytest.raises(ValueError, match="one pose per state"):
        rec.log_episode_trajectory(0, [1, 2, 3], poses=np.zeros((2, 3)))
    rec.log_episode_trajectory(0, [paper50_model.start])
    rec.close()
    rec.close()
    assert verify_recording(tmp_path / "x.rrd")[0]
    with pytest.raises(ValueError, match="world"):
        Recorder.create(tmp_path / "y.rrd", paper50, paper50_model, method="st-ql", config={},
                        seed=0, world="moon")


def test_metadata_names_versions_and_commit(synthetic, tmp_path):
    path, _ = synthetic
    table = read_table(path, ["/meta"], None)
    doc = table.column("/meta:TextDocument:text").to_pylist()[0][0]
    for word in ("rnh-ql", "paper-50", "rerun-sdk", "git_commit", "alpha"):
        assert word in doc
    if (REPO / ".git").exists():  # a checkout (an sdist has no history to name)
        commit = git_commit(REPO)
        assert commit is not None and len(commit.split("+")[0]) == 40
        assert int(commit.split("+")[0], 16) >= 0  # hexadecimal
    assert git_commit(tmp_path) is None  # outside a repository: no commit, no error


def _comparison_parts(tmp_path, paper50, paper50_model, runs, rid) -> list[Path]:
    """A synthetic 20-episode part file per (method, seed) of a comparison ``rid``."""
    parts = []
    for method, seed in runs:
        part = tmp_path / f"{method}-s{seed}.rrd"
        record_synthetic(part, paper50, paper50_model, episodes=20, record_every=10,
                         values_every=10, method=method, seed=seed,
                         prefix=run_prefix(method, seed), recording_id=rid, blueprint=False)
        parts.append(part)
    return parts


def test_comparison_parts_gather_into_one_file(tmp_path, paper50, paper50_model):
    rid = str(uuid.uuid4())
    runs = [("rnh-ql", 0), ("st-ql", 0)]
    parts = _comparison_parts(tmp_path, paper50, paper50_model, runs, rid)
    out = gather_comparison(tmp_path / "compare.rrd", parts, paper50, runs, recording_id=rid)
    assert verify_recording(out)[0]
    for method, seed in runs:
        ent = f"/{run_prefix(method, seed)}/world/robot"
        assert len(positions(read_table(out, [ent], "step"), ent)) > 0


def test_runs_share_one_file_in_process(tmp_path, paper50, paper50_model):
    path = tmp_path / "shared.rrd"
    with RecordingFile(path) as f:
        for method in ("rnh-ql", "haql"):
            rec = Recorder.create(None, paper50, paper50_model, method=method, config={},
                                  seed=1, file=f, prefix=run_prefix(method, 1), blueprint=False)
            rec.log_episode_trajectory(0, [paper50_model.start,
                                           paper50_model.next_state[paper50_model.start, 0]])
    assert verify_recording(path)[0]
    table = read_table(path, ["/runs/haql/s1/world/robot"], "step")
    assert table.num_rows == 2


CHILD = textwrap.dedent("""
    import signal, sys, time
    import numpy as np
    signal.signal(signal.SIGINT, signal.default_int_handler)  # even if the parent ignores it
    from scenarios.recording.recorder import Recorder
    from sim.grid import build_model
    from sim.scenario_io import resolve_scenario
    sc = resolve_scenario("paper-50")
    m = build_model(sc)
    rng = np.random.default_rng(0)
    rec = Recorder.create(sys.argv[1], sc, m, method="rnh-ql", config={}, seed=0,
                          flush_interval_s=0.2)
    def train():
        ep = 0
        while True:
            states = m.next_state[m.start, rng.integers(0, 4, 600)]
            rec.log_episode_trajectory(ep, np.concatenate([[m.start], states]))
            rec.log_episode_metrics([ep], [600], [False], [600.0])
            if ep == 20:
                print("ready", flush=True)
            ep += 1
            time.sleep(0.005)
    if sys.argv[2] == "with":
        with rec:
            train()
    else:
        train()  # no handler at all: the atexit hook closes the file
""")


@pytest.mark.parametrize("mode", ["with", pytest.param("atexit", marks=pytest.mark.slow)])
def test_ctrl_c_leaves_a_verified_recording(tmp_path, mode):
    path = tmp_path / "interrupted.rrd"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(path), mode], cwd=REPO, env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "ready", child.stderr.read()
        time.sleep(0.3)
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
    assert "KeyboardInterrupt" in err
    assert path.exists() and not path.with_name(path.name + ".part").exists()
    ok, msg = verify_recording(path)
    assert ok, msg
    table = read_table(path, ["/world/robot"], "step")
    assert table.num_rows >= 21 * 601


def test_comparison_summary_curves_are_medians_of_ratio_of_sums():
    from scenarios.recording.summary import WINDOW, summary_curves

    n = 2 * WINDOW
    # seed A: a 1-step episode worth 100 among 600-step episodes worth 600
    a = {"key": "a", "steps_per_episode": [1] + [600] * (n - 1),
         "return_per_episode": [100.0] + [600.0] * (n - 1), "success_per_episode": [1] * n}
    b = {"key": "b", "steps_per_episode": [600] * n, "return_per_episode": [0.0] * n,
         "success_per_episode": [0] * n}
    curves = summary_curves([a, b], lambda r: "m")["m"]["reward_per_step"]
    episodes, q25, med, q75 = curves
    i = int(np.flatnonzero(episodes == WINDOW)[0])  # the first full window
    ratio_a = (100.0 + 600.0 * (WINDOW - 1)) / (1 + 600 * (WINDOW - 1))
    assert med[i] == pytest.approx((ratio_a + 0.0) / 2)  # type-7 median of two seeds
    assert q25[i] < med[i] < q75[i]
    succ = summary_curves([a, b], lambda r: "m")["m"]["success"]
    assert succ[2][-1] == pytest.approx(0.5)


def test_comparison_blueprint_has_one_legend_entry_per_method():
    from scenarios.recording import summary

    names = {}

    class Stream:
        def log(self, ent, arch, static=False):
            if isinstance(arch, __import__("rerun").SeriesLines):
                names[ent] = arch.names.as_arrow_array().to_pylist()

        def send_columns(self, *a, **k):
            pass

    ep = np.arange(1.0, 11.0)
    curves = {m: {f: np.stack([ep, ep, ep, ep]) for f in summary.FIGURES}
              for m in ("rnh-ql", "dyna-q")}
    summary.log_summary(Stream(), curves)
    for fig in summary.FIGURES:
        per_view = {n for ent, ns in names.items() if ent.startswith(f"summary/{fig}/")
                    for n in ns}
        assert per_view == {"rnh-ql", "dyna-q"}  # q25/q75 share the median's name


def _views(node):
    """Every view of a blueprint (containers walked depth first)."""
    import rerun.blueprint as rrb

    if isinstance(node, rrb.Blueprint):
        node = node.root_container
    if isinstance(node, rrb.View):
        return [node]
    return [v for child in getattr(node, "contents", []) for v in _views(child)]


def test_route_recording_shows_only_panels_with_data(paper50):
    import rerun.blueprint as rrb

    from scenarios.recording.blueprint import route_blueprint, run_blueprint

    route_views = _views(route_blueprint("", paper50))
    assert route_views and not any(isinstance(v, rrb.TimeSeriesView) for v in route_views)
    assert any(isinstance(v, rrb.TimeSeriesView) for v in _views(run_blueprint("", paper50)))


def test_comparison_blueprint_curves_are_the_summary_only(paper50):
    import rerun.blueprint as rrb

    from scenarios.recording.blueprint import comparison_blueprint

    runs = [(m, s) for m in ("rnh-ql", "st-ql") for s in range(3)]
    curves = [v for v in _views(comparison_blueprint(runs, paper50, run_prefix))
              if isinstance(v, rrb.TimeSeriesView)]
    assert len(curves) == 4
    for v in curves:  # rooted at summary/<figure>: no per-seed series from runs/...
        assert str(v.origin).startswith("/summary/")


def test_comparison_file_has_the_summary_before_the_runs(tmp_path, paper50, paper50_model):
    """The web viewer reads front to back: the curves it draws first must come first."""
    from scenarios.recording.recorder import rerun_cli
    from scenarios.recording.summary import summary_curves

    rid = str(uuid.uuid4())
    runs = [("rnh-ql", 0), ("st-ql", 0)]
    parts = _comparison_parts(tmp_path, paper50, paper50_model, runs, rid)
    records = [{"key": method, "steps_per_episode": [5] * 20,
                "return_per_episode": [1.0] * 20, "success_per_episode": [1] * 20}
               for method, _ in runs]
    curves = summary_curves(records, lambda r: r["key"])
    out = gather_comparison(tmp_path / "c.rrd", parts, paper50, runs, recording_id=rid,
                            curves=curves)
    assert verify_recording(out)[0]
    listing = subprocess.run([rerun_cli(), "rrd", "print", str(out)], capture_output=True,
                             text=True, timeout=60, check=True).stdout
    chunks = [line for line in listing.splitlines() if line.startswith("Chunk(")]
    first_run = min(i for i, c in enumerate(chunks) if " - /runs/" in c)
    summary = [i for i, c in enumerate(chunks) if " - /summary/" in c]
    assert summary and max(summary) < first_run
    for method, seed in runs:  # and nothing of the parts is lost
        ent = f"/{run_prefix(method, seed)}/world/robot"
        assert len(positions(read_table(out, [ent], "step"), ent)) > 0


def test_the_comparison_shows_the_greedy_test_share():
    """The summary's greedy curve: per method the share of seeds whose latest greedy test from
    S was optimal (every 10th episode, where the tests fall)."""
    from scenarios.recording.summary import summary_curves

    def rec(seed, lengths):
        return {"method": "m", "seed": seed, "optimal_route_length": 5,
                "steps_per_episode": [5] * 30, "return_per_episode": [1.0] * 30,
                "success_per_episode": [1] * 30, "test_episodes": [10, 20, 30],
                "test_route_length": lengths}

    curves = summary_curves([rec(0, [5, 5, 5]), rec(1, [-1, 5, 7])], lambda r: r["method"])
    episodes, q25, med, q75 = curves["m"]["greedy"]
    assert list(episodes) == [10, 20, 30]
    assert list(med) == [0.5, 1.0, 0.5] and list(q25) == list(med) == list(q75)
