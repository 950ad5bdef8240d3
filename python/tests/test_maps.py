"""Maps and scenarios: numpy arrays in, files read, frames kept, bad input refused."""

import numpy as np
import pytest

import bi_am_rrt as b


def test_a_bool_array_round_trips():
    a = np.zeros((20, 30), dtype=bool)
    a[5:8, 10:25] = True
    m = b.Map.from_array(a, 0.5)
    assert m.shape == (20, 30)
    assert m.resolution_m == 0.5
    assert m.width_m == 15.0 and m.height_m == 10.0
    assert (m.to_array() == a).all()
    # Row 0 is the top: y down from the top-left corner.
    assert not m.is_free((6.0, 3.0)) and m.is_free((6.0, 1.0))
    assert m.extent == (0.0, 15.0, 10.0, 0.0)


def test_a_uint8_array_takes_non_zero_as_occupied():
    a = np.zeros((4, 4), dtype=np.uint8)
    a[1, 2] = 100
    assert (b.Map.from_array(a, 1.0).to_array() == (a != 0)).all()


@pytest.mark.parametrize(
    "array, words",
    [
        (np.zeros((4, 4), dtype=np.float64), "bool or uint8"),
        (np.zeros((4, 4, 3), dtype=bool), "2 dimensions"),
        (np.zeros((0, 4), dtype=bool), "1 to 65535"),
        ([[0, 1], [1, 0]], "bool or uint8"),
    ],
)
def test_bad_arrays_are_value_errors(array, words):
    with pytest.raises(ValueError, match=words):
        b.Map.from_array(array, 1.0)


@pytest.mark.parametrize("r", [float("nan"), 0.0, -1.0, 1e-30, float("inf")])
def test_bad_resolutions_are_value_errors(r):
    with pytest.raises(ValueError, match="resolution"):
        b.Map.from_array(np.zeros((4, 4), dtype=bool), r)


def test_a_scenario_refuses_a_goal_in_a_wall():
    a = np.zeros((10, 10), dtype=bool)
    a[:, 5] = True
    m = b.Map.from_array(a, 1.0)
    with pytest.raises(ValueError, match="goal 1"):
        b.Scenario(m, (1.5, 1.5), [(5.5, 5.5)])
    with pytest.raises(ValueError, match="finite"):
        b.Scenario(m, (float("nan"), 1.5), [(8.5, 5.5)])


def test_an_origin_gives_the_ros_frame():
    a = np.zeros((10, 20), dtype=bool)
    a[0, 0] = True  # top-left cell
    m = b.Map.from_array(a, 0.5, origin=(-3.0, 2.0))
    # The top-left cell spans x -3..-2.5 and y 6.5..7 in the ROS frame (y up).
    assert not m.is_free((-2.75, 6.75)) and m.is_free((-2.75, 2.25))
    assert m.extent == (-3.0, 7.0, 2.0, 7.0)
    s = b.Scenario(m, (-2.0, 3.0), [(5.0, 6.0)])
    assert s.start == pytest.approx((-2.0, 3.0)) and s.goals[0] == pytest.approx((5.0, 6.0))


def test_builtin_scenarios():
    assert "bug_trap" in b.builtin_names()
    s = b.Scenario.builtin("bug_trap")
    assert s.name == "bug_trap" and len(s.goals) == 3
    assert [x.name for x in b.load_scenarios("builtin", ["maze", "open"])] == ["maze", "open"]
    with pytest.raises(ValueError, match="no built-in scenario"):
        b.Scenario.builtin("nowhere")


def test_reference_maps_and_scenario_files(shared_maps):
    office = b.Map.from_png(shared_maps / "office.png", 0.25)
    assert office.resolution_m == 0.25
    scs = b.load_scenarios(shared_maps / "scenarios.toml")
    assert {"bug_trap", "maze", "office", "empty"} <= {s.name for s in scs}
    with pytest.raises(b.BiAmRrtError, match="no_such.png"):
        b.Map.from_png(shared_maps / "no_such.png", 1.0)


def test_a_nav2_map_keeps_its_frame(shared_maps):
    depot = b.Map.from_ros(shared_maps / "real" / "depot.yaml")
    assert depot.resolution_m == pytest.approx(0.05)
    assert depot.origin is not None
    (s,) = b.load_scenarios(shared_maps / "real" / "scenarios.toml", ["depot"])
    # The scenario file's positions, in the map frame, come back as written.
    assert s.start == pytest.approx((0.425, 14.675), abs=1e-5)
    assert s.goals[1] == pytest.approx((16.325, 1.425), abs=1e-5)
    assert s.map.is_free(s.start)
