"""A Python run is a host-sim run: the same trail and lengths to the bit (seed, virtual clock)."""

import json

import pytest

import bi_am_rrt as b


@pytest.mark.parametrize(
    "scenario, planner, seed, all_goals",
    [("bug_trap", "tuned", 1, True), ("maze", "paper", 7, False)],
)
def test_python_run_equals_host_sim_run(tmp_path, host_sim, scenario, planner, seed, all_goals):
    out = tmp_path / "run"
    host_sim(
        "run", "--scenarios", "builtin", "--maps", scenario, "--planners", planner,
        "--seed", str(seed), "--clock", "virtual", "--t-exp-ms", "5", "--out", str(out),
        *(["--all-goals"] if all_goals else []),
    )
    theirs = json.loads((out / "result.json").read_text())
    ours = b.run(b.Scenario.builtin(scenario), planner=planner, seed=seed, all_goals=all_goals, t_exp_ms=5)
    assert len(ours) == len(theirs) > 0
    for o, t in zip(ours, theirs):
        assert o["trail"] == t["trail"]
        for k in ("path_length_m", "optimal_m", "reached", "collisions", "calls", "nodes_at_goal",
                  "search_time_s", "cost_at_start_m", "final_nodes", "min_clearance_m"):
            assert o[k] == t[k], k


def test_the_nav2_depot_the_same(tmp_path, host_sim, shared_maps):
    real = shared_maps / "real" / "scenarios.toml"
    out = tmp_path / "run"
    host_sim("run", "--scenarios", str(real), "--maps", "depot", "--clock", "virtual",
             "--seed", "2", "--t-exp-ms", "5", "--out", str(out), "--no-optimum")
    theirs = json.loads((out / "result.json").read_text())
    (s,) = b.load_scenarios(real, ["depot"])
    ours = b.run(s, seed=2, optimum=False, t_exp_ms=5)
    assert ours[0]["trail"] == theirs[0]["trail"]
    assert ours[0]["path_length_m"] == theirs[0]["path_length_m"]
