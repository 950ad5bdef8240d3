"""The planner from Python (5 ms calls: a 150 ms call of virtual time is 150 ms of work): it reaches goals, keeps the promises (a free waypoint, a named
refusal), repeats itself with a seed, and lets other threads run while it plans."""

import math
import threading

import numpy as np
import pytest

import bi_am_rrt as b


def drive(planner, start, goal, calls=400):
    planner.set_goal(goal)
    agent, trail = start, [start]
    for _ in range(calls):
        p = planner.plan(agent)
        agent = p.waypoint
        trail.append(agent)
        if p.status == "arrived":
            return True, trail
    return False, trail


def corridor_map():
    a = np.zeros((40, 60), dtype=bool)
    a[0:30, 20] = True  # a wall from the top, open at the bottom
    a[10:40, 40] = True  # and one from the bottom, open at the top
    return b.Map.from_array(a, 0.5)


def test_reaches_a_goal_round_two_walls_without_touching_them():
    m = corridor_map()
    s = b.Scenario(m, (2.0, 2.0), [(28.0, 18.0)])
    ok, trail = drive(b.Planner(s, seed=3, t_exp_ms=5), s.start, s.goals[0])
    assert ok
    # Every segment it drove stays in free cells (sampled at a tenth of a cell).
    for (x0, y0), (x1, y1) in zip(trail, trail[1:]):
        n = max(2, int(math.hypot(x1 - x0, y1 - y0) / 0.05))
        for k in range(n + 1):
            t = k / n
            assert m.is_free((x0 + t * (x1 - x0), y0 + t * (y1 - y0)))


def test_same_seed_same_trail_another_seed_another():
    s = b.Scenario.builtin("maze")
    _, t1 = drive(b.Planner(s, seed=5, t_exp_ms=5), s.start, s.goals[0])
    _, t2 = drive(b.Planner(s, seed=5, t_exp_ms=5), s.start, s.goals[0])
    _, t3 = drive(b.Planner(s, seed=6, t_exp_ms=5), s.start, s.goals[0])
    assert t1 == t2
    assert t1 != t3


@pytest.mark.parametrize("name", ["paper", "RT-RRT*", "AM-RRT*(E)", "Bi-AM-RRT*(D)", "tuned@e_max=3"])
def test_named_planners_reach_the_open_goal(name):
    s = b.Scenario.builtin("open")
    p = b.Planner(s, planner=name, nodes=4096, t_exp_ms=5)
    assert p.nodes == 4096
    ok, _ = drive(p, s.start, s.goals[0], calls=600)
    assert ok, p.name


def test_refusals_are_named_exceptions():
    s = b.Scenario.builtin("bug_trap")
    p = b.Planner(s, t_exp_ms=5)
    assert p.nodes == 8192, "the default arena on a map whose roadmap fits it"
    arr = s.map.to_array()
    row, col = map(int, np.argwhere(arr)[0])
    wall = ((col + 0.5) * s.map.resolution_m, (row + 0.5) * s.map.resolution_m)
    with pytest.raises(b.InWallError, match="goal"):
        p.set_goal(wall)
    with pytest.raises(b.PositionError, match="outside the map"):
        p.set_goal((-5.0, 3.0))
    with pytest.raises(ValueError, match="finite"):
        p.plan((float("nan"), 1.0))
    with pytest.raises(b.InWallError, match="agent"):
        p.plan(wall)
    with pytest.raises(ValueError, match="nodes=1000"):
        b.Planner(s, nodes=1000)
    with pytest.raises(ValueError, match="no_such_field"):
        b.Planner(s, params={"no_such_field": 1})
    with pytest.raises(ValueError, match="planner"):
        b.Planner(s, planner="Dijkstra")
    with pytest.raises(b.InWallError, match="start"):
        b.Planner(s.map, start=wall)
    # The planner is still usable after the refusals.
    p.set_goal(s.goals[0])
    assert p.plan(s.start).status in ("searching", "following", "arrived")


def test_params_reach_the_configuration():
    s = b.Scenario.builtin("open")
    p = b.Planner(s, params={"e_max": 2.5, "bidirectional": False}, t_exp_ms=20)
    assert float(p.params()["e_max"]) == 2.5
    assert p.params()["bidirectional"] == "false"
    assert float(p.params()["t_exp"].rstrip("ms")) == pytest.approx(20) or "20" in p.params()["t_exp"]


def test_an_obstacle_on_the_path_is_never_crossed():
    s = b.Scenario.builtin("open")
    p = b.Planner(s, seed=2, t_exp_ms=5)
    p.set_goal(s.goals[0])
    agent = s.start
    first = p.plan(agent)
    path = p.path()
    assert len(path) >= 2
    mid = path[len(path) // 2]
    centre, r = (float(mid[0]), float(mid[1])), 2.0
    oid = p.add_obstacle(centre, r)
    arrived = False
    for _ in range(600):
        q = p.plan(agent)
        (x0, y0), (x1, y1) = agent, q.waypoint
        # The segment to the waypoint keeps out of the disc.
        dx, dy = x1 - x0, y1 - y0
        L2 = dx * dx + dy * dy
        t = 0.0 if L2 == 0 else max(0.0, min(1.0, ((centre[0] - x0) * dx + (centre[1] - y0) * dy) / L2))
        assert math.hypot(x0 + t * dx - centre[0], y0 + t * dy - centre[1]) >= r - 1e-4
        agent = q.waypoint
        if q.status == "arrived":
            arrived = True
            break
    assert first.status in ("searching", "following")
    assert arrived
    p.remove_obstacle(oid)
    with pytest.raises(ValueError, match="obstacle"):
        p.remove_obstacle(oid)


def test_live_cells_close_a_door_and_the_agent_holds_or_goes_round():
    a = np.zeros((20, 40), dtype=bool)
    a[:, 20] = True
    a[8:12, 20] = False  # a door
    m = b.Map.from_array(a, 1.0)
    s = b.Scenario(m, (5.5, 10.5), [(35.5, 10.5)])
    p = b.Planner(s, live_cells=True, t_exp_ms=5)
    p.set_goal(s.goals[0])
    assert p.set_cells((20, 8), (20, 11), True) == 4
    agent = s.start
    for _ in range(50):
        q = p.plan(agent)
        agent = q.waypoint
        assert agent[0] < 20.0  # never through the closed door
    assert q.status in ("searching", "waiting")
    assert p.set_cells((20, 8), (20, 11), False) == 4
    with pytest.raises(ValueError, match="set_cells"):
        b.Planner(s, t_exp_ms=5).set_cells((0, 0), (1, 1), True)


def test_trees_and_path_are_numpy_arrays():
    s = b.Scenario.builtin("bug_trap")
    p = b.Planner(s, planner="Bi-AM-RRT*(D)", seed=4, t_exp_ms=5)
    p.set_goal(s.goals[0])
    for _ in range(3):
        p.grow()
    t, r = p.tree(), p.reverse_tree()
    n = len(t["xy"])
    assert t["xy"].shape == (n, 2) and t["parent"].shape == (n,) and t["cost"].shape == (n,)
    assert (t["parent"] == -1).sum() == 1
    assert (t["parent"] < n).all()
    root = int(np.nonzero(t["parent"] == -1)[0][0])
    assert tuple(t["xy"][root]) == pytest.approx(s.start)
    assert r["xy"].shape[1] == 2
    # Two trees: the reverse one grows until they meet.
    assert len(r["xy"]) > 0 or p.stats()["met"]
    path = p.path()
    assert path.ndim == 2 and path.shape[1] == 2


def test_the_interpreter_runs_while_the_planner_plans():
    s = b.Scenario.builtin("office_200")
    p = b.Planner(s, clock="wall", t_exp_ms=300)
    p.set_goal(s.goals[0])
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)

    t = threading.Thread(target=count)
    t.start()
    before = len(ticks)
    p.grow()
    during = len(ticks) - before
    stop.set()
    t.join()
    # A Python thread holding no lock of ours counted while the 300 ms call ran.
    assert during > 1000
