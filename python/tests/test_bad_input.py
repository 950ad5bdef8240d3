"""No input reaches a Rust panic: hundreds of bad values thrown at every entry point come back
as ordinary Python exceptions (a panic would surface as pyo3's PanicException, a
BaseException that `except Exception` does not catch, and fail the test)."""

import math
import random

import numpy as np
import pytest

import bi_am_rrt as b

BAD_NUMBERS = [float("nan"), float("inf"), -float("inf"), -1.0, 0.0, 1e-30, 1e30, -1e30, 3.4e38]


def numbers(rng):
    return rng.choice(BAD_NUMBERS + [rng.uniform(-100, 100), rng.uniform(0, 70)])


def point(rng):
    return (numbers(rng), numbers(rng))


def call(f, *args, **kw):
    try:
        return f(*args, **kw)
    except Exception:  # noqa: BLE001 - any ordinary exception is a refusal; a panic is not one
        return None


def test_random_bad_input_never_panics():
    rng = random.Random(45)
    s = b.Scenario.builtin("bug_trap")
    m = s.map
    p = b.Planner(s, t_exp_ms=1)
    live = b.Planner(s, t_exp_ms=1, live_cells=True, nodes=2048)
    table = b.DiffusionTable.bake(b.Scenario.builtin("open"))
    added = []
    for _ in range(300):
        call(p.set_goal, point(rng))
        call(p.plan, point(rng))
        oid = call(p.add_obstacle, point(rng), numbers(rng), velocity=point(rng))
        if oid is not None:
            added.append(oid)
        call(p.update_obstacle, rng.randrange(0, 20), point(rng), numbers(rng))
        call(p.remove_obstacle, rng.randrange(0, 20))
        call(live.set_cells, (rng.randrange(0, 70000), rng.randrange(0, 70000)), (rng.randrange(0, 70), rng.randrange(0, 70)), rng.random() < 0.5)
        call(live.plan, point(rng))
        call(m.is_free, point(rng))
        call(table.distance, point(rng), point(rng))
        call(b.exact_optimum, m, point(rng), point(rng))
        call(b.geodesic_distance, m, point(rng), point(rng))
        call(b.Scenario, m, point(rng), [point(rng)], robot_radius=numbers(rng))
        call(b.Map.from_array, np.zeros((rng.randrange(0, 5), rng.randrange(0, 5)), dtype=rng.choice([bool, np.uint8, np.int64])), numbers(rng), origin=point(rng))
    for name in ["", "tuned@", "tuned@e_max=", "tuned@e_max=nan", "tuned@e_max=-1", "all", "paper,tuned", "@@"]:
        call(b.Planner, s, planner=name)
    for params in [{"e_max": float("nan")}, {"sigma": -1}, {"t_exp": "x"}, {"bidirectional": 3}, {1: 2}]:
        call(b.Planner, s, params=params)
    for kw in [{"nodes": -1}, {"nodes": 2**70}, {"seed": -1}, {"clock": "cpu"}, {"t_exp_ms": 0}, {"t_exp_ms": math.nan}, {"robot_radius": 1e9}]:
        call(b.Planner, s, **kw)
    for kw in [{"repeats": 0}, {"planners": ""}, {"jobs": 0, "t_exp_ms": 1, "optimum": False}, {"pace": "slow"}, {"t_exp_ms": -5}]:
        call(b.experiment, b.Scenario.builtin("open"), **kw)
    # And the planner still works after all of it (its obstacles gone).
    for oid in added:
        call(p.remove_obstacle, oid)
    p.set_goal(s.goals[0])
    assert p.plan(s.start).status in ("searching", "following", "arrived", "waiting")


@pytest.mark.parametrize("r", [0.6, 1.2])
def test_a_robot_radius_keeps_the_disc_clear(r):
    s = b.Scenario.builtin("bug_trap")
    p = b.Planner(s, robot_radius=r, t_exp_ms=5)
    p.set_goal(s.goals[0])
    walls = np.argwhere(s.map.to_array()) + 0.5  # (row, col) centres
    agent = s.start
    for _ in range(300):
        q = p.plan(agent)
        agent = q.waypoint
        # The disc's centre stays at least r from every wall cell's square (1 m cells).
        dx = np.maximum(np.abs(walls[:, 1] - agent[0]) - 0.5, 0.0)
        dy = np.maximum(np.abs(walls[:, 0] - agent[1]) - 0.5, 0.0)
        assert np.hypot(dx, dy).min() >= r - 1e-3
        if q.status == "arrived":
            break
    assert q.status == "arrived"
