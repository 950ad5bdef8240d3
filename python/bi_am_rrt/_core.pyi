"""Type stubs of the extension module ``bi_am_rrt._core`` (the Rust side)."""

from os import PathLike
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Xy = Tuple[float, float]
StrPath = Union[str, PathLike]

class BiAmRrtError(Exception):
    """A file, a table or a run the library could not use (the message says why)."""

class PositionError(ValueError):
    """A position the planner refuses: not finite, outside the map, in a wall, or cut off."""

class InWallError(PositionError):
    """A goal or an agent inside an obstacle, or closer to a wall than the robot's radius."""

class Map:
    """An occupancy grid map (immutable). Build one with ``from_ros``, ``from_png`` or
    ``from_array``.

    A map read from a ROS YAML, or given an ``origin``, takes positions in its ROS frame
    (metres, y up from the origin); any other map metres from its top-left corner, y down."""

    @staticmethod
    def from_ros(yaml_path: StrPath) -> Map:
        """Reads a ROS map_server map: the YAML file and the PGM or PNG image it names."""
    @staticmethod
    def from_png(path: StrPath, resolution_m: float) -> Map:
        """Reads a PNG map (dark pixels are walls) with cells of ``resolution_m`` metres."""
    @staticmethod
    def from_array(
        array: npt.NDArray[Union[np.bool_, np.uint8]],
        resolution_m: float,
        origin: Optional[Xy] = None,
    ) -> Map:
        """A map from a 2-D ``bool`` (True: occupied) or ``uint8`` (non-zero: occupied)
        array, rows from the top. With ``origin`` positions are in a ROS-like frame (y up,
        the lower-left corner at ``origin``). Raises ``ValueError`` for another dtype, shape
        or a resolution outside 0.1 mm - 1 km."""
    @property
    def shape(self) -> Tuple[int, int]:
        """``(rows, cols)``."""
    @property
    def resolution_m(self) -> float:
        """Cell side in metres."""
    @property
    def width_m(self) -> float: ...
    @property
    def height_m(self) -> float: ...
    @property
    def origin(self) -> Optional[Xy]:
        """The ROS origin (the lower-left corner), or None for the top-left frame."""
    @property
    def source(self) -> str: ...
    @property
    def extent(self) -> Tuple[float, float, float, float]:
        """matplotlib's ``extent`` (left, right, bottom, top) for ``imshow(to_array(),
        origin="upper")``."""
    def to_array(self) -> npt.NDArray[np.bool_]:
        """The cells (True: occupied), rows from the top."""
    def is_free(self, p: Xy) -> bool:
        """Whether a point is in a free cell (False outside the map)."""

class Scenario:
    """A map, a start, goals in order and the robot's radius."""

    def __init__(
        self,
        map: Map,
        start: Xy,
        goals: Sequence[Xy],
        name: str = "custom",
        sigma_m: Optional[float] = None,
        robot_radius: float = 0.0,
    ) -> None:
        """Positions in the map's frame. Raises ``ValueError`` for a start or a goal outside
        the map, in a wall or where the robot's disc has no room."""
    @staticmethod
    def builtin(name: str) -> Scenario:
        """A built-in scenario (``builtin_names()``)."""
    def with_robot_radius(self, radius: float) -> Scenario:
        """This scenario for a robot of ``radius`` metres (the map inflated for its disc)."""
    @property
    def name(self) -> str: ...
    @property
    def map(self) -> Map: ...
    @property
    def start(self) -> Xy: ...
    @property
    def goals(self) -> List[Xy]: ...
    @property
    def robot_radius(self) -> float: ...
    @property
    def sigma_m(self) -> float:
        """The trees' connection distance the planners get (metres)."""
    @property
    def source(self) -> str: ...

def load_scenarios(path: StrPath, names: Optional[Sequence[str]] = None) -> List[Scenario]:
    """The scenarios of a ``host-sim`` scenario file (TOML), or of the built-in set with
    ``path="builtin"``; ``names`` keeps those."""

def builtin_names() -> List[str]:
    """The names of the built-in scenarios."""

class DiffusionTable:
    """A diffusion table (the paper's assisting metric d_D), in ``host-sim bake``'s format."""

    @staticmethod
    def bake(of: Union[Scenario, Map]) -> DiffusionTable:
        """Bakes the table of a scenario (the region its start reaches, for its robot) or of a
        map (its largest free region)."""
    @staticmethod
    def load(path: StrPath) -> DiffusionTable:
        """Reads a table file; its checksum is verified (``BiAmRrtError`` otherwise)."""
    def save(self, path: StrPath) -> None: ...
    def to_bytes(self) -> bytes: ...
    def distance(self, a: Xy, b: Xy) -> float:
        """d_D between two points in planner coordinates (top-left frame, y down)."""
    def __len__(self) -> int: ...

class Progress:
    """What a ``plan`` or ``grow`` call did and where the agent should go."""

    waypoint: Xy
    status: Literal["no_goal", "searching", "following", "arrived", "waiting", "unreachable", "evading"]
    reason: Optional[
        Literal["path_blocked", "agent_in_obstacle", "agent_blocked", "out_of_time", "giving_way", "cornered"]
    ]
    work: int
    goal_in_tree: bool
    goal_cost: Optional[float]
    nodes: int
    reverse_nodes: int
    expansions: int
    advanced: bool
    tree_full: bool

class Planner:
    """A planner on a scenario's map: ``"tuned"`` (the default), ``"paper"`` or any name of
    ``planner_names()`` (with ``@field=value`` overrides).

    Each ``plan(agent)`` is one control period of ``t_exp`` (150 ms unless ``t_exp_ms``) on
    the planner's clock: ``"virtual"`` (work units at 12 ns; the same answer on every
    machine) or ``"wall"``. ``nodes`` is 2048, 4096, 8192, 16384 or 65000 per tree (default:
    8192, or the smallest that holds the scenario's roadmap)."""

    def __init__(
        self,
        scenario: Union[Scenario, Map],
        planner: str = "tuned",
        seed: int = 1,
        nodes: Optional[int] = None,
        start: Optional[Xy] = None,
        clock: Literal["virtual", "wall"] = "virtual",
        t_exp_ms: Optional[float] = None,
        params: Optional[Dict[str, Any]] = None,
        live_cells: bool = False,
        table: Optional[DiffusionTable] = None,
        robot_radius: Optional[float] = None,
    ) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def nodes(self) -> int: ...
    @property
    def map(self) -> Map: ...
    def params(self) -> Dict[str, str]:
        """Every value of the parameter table as this planner has it."""
    def set_goal(self, goal: Xy) -> None:
        """Raises ``InWallError`` for a goal in a wall, ``PositionError`` for one outside the
        map or cut off."""
    def plan(self, agent: Xy) -> Progress:
        """One control period with the agent at ``agent``: the next waypoint and the status."""
    def grow(self) -> Progress:
        """Planning while the agent stands still, for one call's budget."""
    def clock_s(self) -> float:
        """The clock's reading in seconds."""
    def add_obstacle(self, center: Xy, radius: float, velocity: Optional[Xy] = None) -> int:
        """Adds a disc (moving at ``velocity`` m/s if given); returns its id."""
    def update_obstacle(self, id: int, center: Xy, radius: float, velocity: Optional[Xy] = None) -> None: ...
    def remove_obstacle(self, id: int) -> None: ...
    def set_cells(self, a: Tuple[int, int], b: Tuple[int, int], occupied: bool) -> int:
        """Marks or clears a rectangle of cells ``(col, row)`` (rows from the top) on a planner
        made with ``live_cells=True``; returns how many changed."""
    def tree(self) -> Dict[str, npt.NDArray[Any]]:
        """``xy`` (n x 2), ``parent`` (-1 at the root), ``cost`` (metres), ``blocked``."""
    def reverse_tree(self) -> Dict[str, npt.NDArray[Any]]: ...
    def path(self) -> npt.NDArray[np.float64]:
        """The current path from the root (k x 2)."""
    def stats(self) -> Dict[str, Any]: ...

def planner_names() -> List[str]:
    """``tuned``, ``paper`` and Table 1's 20 names."""

def exact_optimum(map: Union[Map, Scenario], a: Xy, b: Xy) -> Optional[Tuple[float, List[Xy]]]:
    """The exact shortest path from ``a`` to ``b``: ``(length_m, points)``, or None."""

def geodesic_distance(map: Union[Map, Scenario], a: Xy, b: Xy) -> float:
    """The shortest path over the 8-connected grid of free cells (d_G), in metres."""

def run(
    scenario: Scenario,
    planner: str = "tuned",
    seed: int = 1,
    all_goals: bool = False,
    clock: Literal["virtual", "cpu", "cpu-mono", "wall"] = "virtual",
    t_exp_ms: Optional[float] = None,
    pace: Literal["full", "paper"] = "full",
    optimum: bool = True,
    params: Optional[Dict[str, Any]] = None,
) -> List[Dict[str, Any]]:
    """``host-sim run``'s drive: one dict per goal (``runs.csv``'s columns, the trail's
    clearance and the ``trail``)."""

def experiment(
    scenarios: Union[Scenario, Sequence[Scenario]],
    planners: Union[str, Sequence[str], None] = None,
    repeats: int = 1,
    seed: int = 1,
    all_goals: bool = False,
    clock: Literal["virtual", "cpu", "cpu-mono", "wall"] = "virtual",
    t_exp_ms: Optional[float] = None,
    pace: Literal["full", "paper"] = "full",
    optimum: bool = True,
    search_only: bool = False,
    jobs: Optional[int] = None,
    out: Optional[StrPath] = None,
    resume: bool = False,
) -> List[Dict[str, Any]]:
    """``host-sim experiment``'s matrix: one dict per goal run (``runs.csv``'s rows)."""
