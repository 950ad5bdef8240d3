"""The simulator: runs and experiments as rows for pandas, the exact optimum, metric data."""

import math

import numpy as np
import pytest

import bi_am_rrt as b


def test_run_returns_a_row_and_a_trail_per_goal():
    s = b.Scenario.builtin("bug_trap")
    rows = b.run(s, seed=2, all_goals=True, t_exp_ms=5)
    assert [r["goal_index"] for r in rows] == [1, 2, 3]
    for r in rows:
        assert r["reached"] and r["collisions"] == 0
        assert r["path_length_m"] >= r["optimal_m"] - 1e-3
        assert r["travelled_ratio"] == pytest.approx(r["path_length_m"] / r["optimal_m"], rel=1e-5)
        trail = np.asarray(r["trail"])
        assert trail.shape[1] == 2
        # The trail's length is the row's path length.
        assert np.linalg.norm(np.diff(trail, axis=0), axis=1).sum() == pytest.approx(r["path_length_m"], rel=1e-4)
    assert rows[0]["trail"][0] == pytest.approx(s.start)


def test_run_without_the_optimum_and_at_the_paper_pace():
    s = b.Scenario.builtin("open")
    (r,) = b.run(s, planner="paper", pace="paper", optimum=False, t_exp_ms=20)
    assert r["optimal_m"] is None and r["reached"]
    with pytest.raises(ValueError, match="virtual"):
        b.run(s, pace="paper", clock="wall")


def test_experiment_rows_make_a_dataframe():
    pd = pytest.importorskip("pandas")
    scs = [b.Scenario.builtin("open"), b.Scenario.builtin("bug_trap")]
    rows = b.experiment(scs, planners=["tuned", "RT-RRT*"], repeats=2, seed=1, jobs=2, t_exp_ms=5)
    df = pd.DataFrame(rows)
    assert len(df) == 2 * 2 * 2
    assert set(df["planner"]) == {"Bi-AM-RRT*(D) tuned", "RT-RRT*"}
    assert df["seed"].tolist().count(1) == 4
    means = df.groupby("planner")["path_length_m"].mean()
    assert (means > 0).all()


def test_experiment_keeps_its_folder_and_refuses_to_overwrite_it(tmp_path):
    s = b.Scenario.builtin("open")
    out = tmp_path / "results"
    rows = b.experiment(s, repeats=1, out=out, optimum=False, t_exp_ms=5)
    assert (out / "runs.csv").is_file() and len(rows) == 1
    with pytest.raises(b.BiAmRrtError, match="already"):
        b.experiment(s, repeats=1, out=out, optimum=False, t_exp_ms=5)
    again = b.experiment(s, repeats=1, out=out, optimum=False, resume=True, t_exp_ms=5)
    assert again == rows  # nothing left to run: the folder's rows


def test_exact_optimum_round_a_wall():
    a = np.zeros((10, 10), dtype=bool)
    a[2:10, 5] = True
    m = b.Map.from_array(a, 1.0)
    d, pts = b.exact_optimum(m, (2.0, 8.0), (8.0, 8.0))
    # Over the wall's top corners (5, 2) and (6, 2).
    assert d == pytest.approx(math.hypot(3, 6) + 1 + math.hypot(2, 6), rel=1e-9)
    assert pts[0] == pytest.approx((2.0, 8.0)) and pts[-1] == pytest.approx((8.0, 8.0))
    a[0:2, 5] = True
    assert b.exact_optimum(b.Map.from_array(a, 1.0), (2.0, 8.0), (8.0, 8.0)) is None


def test_the_optimum_of_a_reference_leg(shared_maps):
    (s,) = b.load_scenarios(shared_maps / "scenarios.toml", ["bug_trap"])
    d, _ = b.exact_optimum(s, s.start, s.goals[0])
    (r,) = b.run(s, seed=1, t_exp_ms=5)
    assert r["optimal_m"] == pytest.approx(d, rel=1e-6)


def test_geodesic_is_no_shorter_than_the_exact_optimum():
    s = b.Scenario.builtin("maze")
    g = b.geodesic_distance(s, s.start, s.goals[0])
    d, _ = b.exact_optimum(s, s.start, s.goals[0])
    assert d <= g <= d * 1.1


def test_a_diffusion_table_round_trips_and_drives_the_same_run(tmp_path):
    s = b.Scenario.builtin("bug_trap")
    t = b.DiffusionTable.bake(s)
    path = tmp_path / "bug_trap.table"
    t.save(path)
    u = b.DiffusionTable.load(path)
    assert u.to_bytes() == t.to_bytes() and len(u) == len(t)
    assert u.distance(s.start, s.goals[0]) > math.dist(s.start, s.goals[0]) * 0.5

    def trail(table):
        p = b.Planner(s, seed=9, table=table, t_exp_ms=5)
        p.set_goal(s.goals[0])
        a, out = s.start, []
        for _ in range(40):
            a = p.plan(a).waypoint
            out.append(a)
        return out

    assert trail(u) == trail(None)
    corrupt = bytearray(t.to_bytes())
    corrupt[len(corrupt) // 2] ^= 0xFF
    path.write_bytes(bytes(corrupt))
    with pytest.raises(b.BiAmRrtError):
        b.DiffusionTable.load(path)
    other = b.DiffusionTable.bake(b.Scenario.builtin("maze"))
    with pytest.raises(b.BiAmRrtError, match="table|map"):
        b.Planner(s, table=other)


def test_the_optimum_and_the_geodesic_refuse_ends_off_the_map_or_in_walls():
    a = np.zeros((10, 10), dtype=bool)
    a[2:10, 5] = True
    m = b.Map.from_array(a, 1.0)
    for f in (b.exact_optimum, b.geodesic_distance):
        with pytest.raises(b.PositionError, match="outside the map"):
            f(m, (2.0, 8.0), (1e30, 3.0))
        with pytest.raises(b.InWallError, match="b "):
            f(m, (2.0, 8.0), (5.5, 5.5))
        with pytest.raises(ValueError, match="finite"):
            f(m, (float("nan"), 8.0), (8.0, 8.0))
