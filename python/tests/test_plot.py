"""The plotting helper draws a map, both trees and the path (matplotlib, Agg)."""

import pytest

import bi_am_rrt as b


def test_draw_planner_writes_a_picture(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from bi_am_rrt.plot import draw_planner, draw_trail

    s = b.Scenario.builtin("bug_trap")
    p = b.Planner(s, planner="Bi-AM-RRT*(D)", t_exp_ms=5)
    p.set_goal(s.goals[0])
    p.grow()
    fig, ax = plt.subplots()
    draw_planner(p, ax, agent=s.start, goal=s.goals[0])
    (row,) = b.run(s, t_exp_ms=5)
    draw_trail(row["trail"], ax, color="k")
    # The map, two edge collections (forward, reverse) and the lines.
    assert len(ax.images) == 1 and len(ax.collections) == 2 and len(ax.lines) >= 3
    # y down from the top-left corner: the axis is inverted.
    assert ax.get_ylim()[0] > ax.get_ylim()[1]
    out = tmp_path / "planner.png"
    fig.savefig(out)
    plt.close(fig)
    assert out.stat().st_size > 5_000
