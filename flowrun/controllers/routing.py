"""Routing controllers: decide which vehicles need a new route, and which one.

The kernel reports, per vehicle, how many edges of its current route lie *after* the edge it
is on (0 on the route's last edge). Routes on offer for an edge come as Flow's
``available_routes[edge]``: a list of ``(edges, fraction)`` pairs whose fractions sum to 1.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from flowrun.controllers.base import takes_env_only

RouteChoice = tuple[Sequence[str], float]


def needs_new_route(edges_left: Sequence[int] | npt.NDArray[np.int_]) -> npt.NDArray[np.bool_]:
    """Which vehicles are on their route's last edge (``edges_left <= 0``).

    Args:
        edges_left: per vehicle, number of route edges after the current one. A negative
            count (e.g. a vehicle the kernel could not place on its route) also asks for one.
    """
    return np.asarray(edges_left) <= 0


def pick_route(choices: Sequence[RouteChoice], rng: np.random.Generator) -> list[str]:
    """Draw one route from ``(edges, fraction)`` pairs with the given probabilities."""
    if not choices:
        raise ValueError("no route available to choose from")
    if len(choices) == 1:
        return list(choices[0][0])
    weights = np.asarray([frac for _, frac in choices], dtype=np.float64)
    if np.any(weights < 0) or weights.sum() <= 0:
        raise ValueError(f"route fractions must be >= 0 with a positive sum, got {weights}")
    index = int(rng.choice(len(choices), p=weights / weights.sum()))
    return list(choices[index][0])


class Router:
    """Base of routing controllers (one instance per vehicle group).

    Args:
        veh_id: Flow's vehicle id (Flow passes it first; informative here).
        router_params: Flow's ``router_params`` dict (kept as given).

    Attributes:
        registered_name: the name configs use (``type: ContinuousRouter``).
    """

    registered_name: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    #: ``True`` for a Flow-style subclass implementing ``choose_route(env)``: the
    #: environment makes one per vehicle (``Cls(veh_id=..., router_params=params)``) and
    #: applies its route every step
    per_vehicle: ClassVar[bool] = False

    def __init__(self, veh_id: str | None = None, router_params: Any = None) -> None:
        self.veh_id = veh_id
        self.router_params = router_params

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.per_vehicle = takes_env_only(cls.choose_route)

    def reroute_mask(
        self, edges_left: Sequence[int] | npt.NDArray[np.int_]
    ) -> npt.NDArray[np.bool_]:
        """Which vehicles of the group get a new route this step (default: none)."""
        return np.zeros(np.asarray(edges_left).shape, dtype=bool)

    def choose_route(
        self, current_edge: str, choices: Sequence[RouteChoice], rng: np.random.Generator
    ) -> list[str] | None:
        """The new route for a vehicle flagged by :meth:`reroute_mask`, or ``None``."""
        return None


class ContinuousRouter(Router):
    """Keep vehicles circling: on its route's last edge a vehicle takes one of the routes
    that start at that edge (Flow's ``available_routes``), drawn by their fractions."""

    registered_name = "ContinuousRouter"

    def reroute_mask(
        self, edges_left: Sequence[int] | npt.NDArray[np.int_]
    ) -> npt.NDArray[np.bool_]:
        """Vehicles on their route's last edge (see :func:`needs_new_route`)."""
        return needs_new_route(edges_left)

    def choose_route(
        self, current_edge: str, choices: Sequence[RouteChoice], rng: np.random.Generator
    ) -> list[str] | None:
        """One of ``choices`` (routes starting at ``current_edge``), or ``None`` if none."""
        if not choices:
            return None
        return pick_route(choices, rng)


class GridRouter(Router):
    """Flow's router of the traffic-light grid: cars drive straight through.

    Flow's ``GridRouter`` gives a car on its route's last edge the route ``[that edge]``,
    i.e. it keeps its route and leaves the grid at the end of its row or column. The grid's
    routes already run straight through, so nothing is ever rerouted.
    """

    registered_name = "GridRouter"

    def choose_route(
        self, current_edge: str, choices: Sequence[RouteChoice], rng: np.random.Generator
    ) -> list[str] | None:
        """``None``: the car keeps its (straight-through) route."""
        return None
