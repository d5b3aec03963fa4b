"""Flow's three forms of ``specify_routes`` (``{start: [edges]}``, ``{start: [(edges, prob),
...]}``, ``{veh_id: route}``) read into a spec's routes and route choices, checked."""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

from flowrun.errors import ConfigError
from flowrun.networks.spec import RouteChoice
from flowrun.suggest import did_you_mean


def parse_routes(
    given: Mapping[str, Any], edges: set[str], links: set[tuple[str, str]] | None, net_file: str
) -> tuple[dict[str, tuple[str, ...]], dict[str, tuple[RouteChoice, ...]]]:
    """Flow's ``specify_routes`` forms as (most likely route, choices) per start edge.

    ``links`` (edge pairs a lane connects) checks that each route is connected; ``None``
    skips that check (a network not built yet). ``net_file`` names the source in messages.

    Raises:
        ConfigError: unknown edge, unconnected consecutive edges, or probabilities that do
            not sum to 1 (``path`` = ``routes.<start edge>``).
    """
    routes: dict[str, tuple[str, ...]] = {}
    choices: dict[str, tuple[RouteChoice, ...]] = {}
    for start, value in given.items():
        where = f"routes.{start}"
        if start not in edges:
            raise ConfigError(
                f"no edge '{start}' in {net_file}{did_you_mean(str(start), edges)}", path=where
            )
        items = list(value) if isinstance(value, list | tuple) else [value]
        if items and all(isinstance(x, str) for x in items):
            options: list[RouteChoice] = [(tuple(items), 1.0)]
        elif items and all(_is_choice(x) for x in items):
            options = [(tuple(x[0]), float(x[1])) for x in items]
        else:
            raise ConfigError(
                f"expected a list of edge names or a list of [edges, probability] pairs, "
                f"got {value!r}",
                path=where,
            )
        total = sum(p for _, p in options)
        if abs(total - 1.0) > 1e-6:
            raise ConfigError(f"route probabilities sum to {total:g}, expected 1", path=where)
        for route, _ in options:
            _check_route(start, route, edges, links, net_file, where)
        routes[start] = max(options, key=lambda o: o[1])[0]
        if len(options) > 1:
            choices[start] = tuple(options)
    return routes, choices


def _is_choice(x: Any) -> bool:
    return (
        isinstance(x, list | tuple)
        and len(x) == 2
        and isinstance(x[0], list | tuple)
        and all(isinstance(e, str) for e in x[0])
        and not isinstance(x[1], bool)
        and isinstance(x[1], int | float)
    )


def _check_route(start: str, route: tuple[str, ...], edges: set[str],
                 links: set[tuple[str, str]] | None, net_file: str,
                 where: str) -> None:  # fmt: skip
    if not route or route[0] != start:
        raise ConfigError(f"a route must begin on its start edge '{start}', got {list(route)}",
                          path=where)  # fmt: skip
    for edge in route:
        if edge not in edges:
            raise ConfigError(
                f"no edge '{edge}' in {net_file}{did_you_mean(edge, edges)}", path=where
            )
    for a, b in itertools.pairwise(route):
        if links is not None and (a, b) not in links:
            raise ConfigError(
                f"the route goes from '{a}' to '{b}' but {net_file} connects no lane of "
                f"'{a}' to '{b}'",
                path=where,
            )
