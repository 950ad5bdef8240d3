"""Drawing a map, a planner's trees and its path with matplotlib (``pip install
bi-am-rrt[plot]``)."""

from __future__ import annotations

from typing import Any, Optional, Sequence, Tuple

import numpy as np

from ._core import Map, Planner

__all__ = ["draw_map", "draw_tree", "draw_planner", "draw_trail"]


def _axes(ax: Any) -> Any:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.gca()


def draw_map(map: Map, ax: Any = None, **imshow: Any) -> Any:
    """Draws the map's walls (black on white) in its own frame; returns the axes."""
    ax = _axes(ax)
    kw = {"cmap": "Greys", "interpolation": "nearest", "vmin": 0, "vmax": 1}
    kw.update(imshow)
    ax.imshow(map.to_array().astype(float), extent=map.extent, origin="upper", **kw)
    ax.set_aspect("equal")
    return ax


def draw_tree(tree: dict, ax: Any = None, color: str = "tab:blue", **line: Any) -> Any:
    """Draws a tree (``Planner.tree()``'s arrays) as its edges; returns the axes."""
    from matplotlib.collections import LineCollection

    ax = _axes(ax)
    xy = np.asarray(tree["xy"])
    parent = np.asarray(tree["parent"])
    child = np.nonzero(parent >= 0)[0]
    segments = np.stack([xy[child], xy[parent[child]]], axis=1) if len(child) else []
    kw = {"linewidths": 0.5, "colors": color}
    kw.update(line)
    ax.add_collection(LineCollection(segments, **kw))
    return ax


def draw_trail(points: Sequence[Tuple[float, float]], ax: Any = None, **line: Any) -> Any:
    """Draws a polyline (a path, or a run's ``trail``); returns the axes."""
    ax = _axes(ax)
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    kw = {"color": "tab:red", "linewidth": 2}
    kw.update(line)
    ax.plot(p[:, 0], p[:, 1], **kw)
    return ax


def draw_planner(
    planner: Planner,
    ax: Any = None,
    agent: Optional[Tuple[float, float]] = None,
    goal: Optional[Tuple[float, float]] = None,
) -> Any:
    """Draws the planner's map, both trees (forward blue, reverse green) and its current
    path (red), with the agent and the goal if given; returns the axes."""
    ax = draw_map(planner.map, ax)
    draw_tree(planner.tree(), ax, color="tab:blue")
    draw_tree(planner.reverse_tree(), ax, color="tab:green")
    path = planner.path()
    if len(path):
        draw_trail(path, ax)
    if agent is not None:
        ax.plot([agent[0]], [agent[1]], "o", color="tab:orange", markersize=7)
    if goal is not None:
        ax.plot([goal[0]], [goal[1]], "*", color="tab:red", markersize=12)
    return ax
