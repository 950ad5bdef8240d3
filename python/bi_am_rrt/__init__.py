"""Bi-AM-RRT* for Python: the planner and the simulator of the ``bi-am-rrt`` Rust crate.

Maps (``Map.from_ros``, ``Map.from_png``, ``Map.from_array``), scenarios (``Scenario``,
``load_scenarios``, ``Scenario.builtin``), metric data (``DiffusionTable``,
``geodesic_distance``), the planner (``Planner``: ``set_goal``, ``plan``, ``grow``, obstacles,
live cells, trees and path as numpy arrays), the simulator (``run``, ``experiment``: rows for
``pandas.DataFrame``; ``exact_optimum``) and a plotting helper (``bi_am_rrt.plot``, with
matplotlib). The guide is ``docs/guides/python.md`` in the repository.
"""

from ._core import (
    BiAmRrtError,
    DiffusionTable,
    InWallError,
    Map,
    Planner,
    PositionError,
    Progress,
    Scenario,
    __version__,
    builtin_names,
    exact_optimum,
    experiment,
    geodesic_distance,
    load_scenarios,
    planner_names,
    run,
)

__all__ = [
    "BiAmRrtError",
    "DiffusionTable",
    "InWallError",
    "Map",
    "Planner",
    "PositionError",
    "Progress",
    "Scenario",
    "__version__",
    "builtin_names",
    "exact_optimum",
    "experiment",
    "geodesic_distance",
    "load_scenarios",
    "planner_names",
    "run",
]
