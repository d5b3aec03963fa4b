"""Flow's traffic-light grid: ``row_num`` x ``col_num`` signalised junctions.

Inner junctions ``center{row * col_num + col}`` sit ``inner_length`` apart (``center0`` at the
origin, rows going up, columns going right). Every row and column is a two-way straight road;
cars drive straight through (no turns), so each junction controls 4 links per lane pair and
Flow's ``GrGr`` (vertical green) / ``rGrG`` (horizontal green) states fit it. Edge names are
Flow's: on row ``i``, eastbound ``bot{i}_{j}`` and westbound ``top{i}_{j}`` (``j`` = index of
the column to its right); on column ``j``, northbound ``right{i}_{j}`` and southbound
``left{i}_{j}`` (``i`` = index of the row above it). Vehicles enter on ``bot{i}_0``,
``top{i}_{col_num}``, ``right0_{j}``, ``left{row_num}_{j}`` (``short_length`` long) and leave on
the opposite ``long_length`` edges.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.checks import check_values
from flowrun.networks.spec import Connection, Edge, NetworkSpec, Node, StartPositions

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    "grid_array": {
        # number of rows / columns of junctions
        "row_num": 3,
        "col_num": 2,
        # length of the edges between junctions, where cars enter, where they leave, m
        "inner_length": None,
        "short_length": None,
        "long_length": None,
        # cars placed at the start on the entering edges of each direction (spacing custom)
        "cars_top": 20,
        "cars_bot": 20,
        "cars_left": 20,
        "cars_right": 20,
    },
    # lanes of the horizontal (rows) and vertical (columns) edges
    "horizontal_lanes": 1,
    "vertical_lanes": 1,
    # speed limit, m/s: a number or {"horizontal": v, "vertical": v}
    "speed_limit": {"horizontal": 35, "vertical": 35},
    # traffic lights at the inner junctions (Flow's optional key)
    "traffic_lights": True,
}

_GRID_KINDS = {"row_num": "count", "col_num": "count", "inner_length": "positive",
               "short_length": "positive", "long_length": "positive", "cars_top": "non_negative",
               "cars_bot": "non_negative", "cars_left": "non_negative",
               "cars_right": "non_negative"}  # fmt: skip


def speed_limits(value: Any) -> tuple[float, float]:
    """``(horizontal, vertical)`` speed limits from a number or Flow's dict.

    Raises:
        ConfigError: not a positive number or a dict with both keys.
    """
    if isinstance(value, dict):
        extra = set(value) - {"horizontal", "vertical"}
        if extra or len(value) != 2:
            raise ConfigError(
                f"expected {{horizontal: v, vertical: v}}, got {value!r}", path="speed_limit"
            )
        check_values(value, {"horizontal": "positive", "vertical": "positive"})
        return float(value["horizontal"]), float(value["vertical"])
    check_values({"speed_limit": value}, {"speed_limit": "positive"})
    return float(value), float(value)


def straight_lines(rows: int, cols: int) -> list[tuple[str, ...]]:
    """Every straight route through the grid, entering edge first (Flow's routes)."""
    lines = []
    for i in range(rows):
        lines.append(tuple(f"bot{i}_{j}" for j in range(cols + 1)))
        lines.append(tuple(f"top{i}_{cols - j}" for j in range(cols + 1)))
    for j in range(cols):
        lines.append(tuple(f"left{rows - i}_{j}" for i in range(rows + 1)))
        lines.append(tuple(f"right{i}_{j}" for i in range(rows + 1)))
    return lines


def grid_spec(p: dict[str, Any]) -> NetworkSpec:
    """Nodes, edges, straight-through connections and routes of the grid (module docstring)."""
    g = p["grid_array"]
    rows, cols = int(g["row_num"]), int(g["col_num"])
    inner, short, long_ = (float(g[k]) for k in ("inner_length", "short_length", "long_length"))
    h_lanes, v_lanes = int(p["horizontal_lanes"]), int(p["vertical_lanes"])
    v_h, v_v = speed_limits(p["speed_limit"])
    kind = "traffic_light" if p["traffic_lights"] else "priority"
    radius = 2.9 + 3.3 * max(h_lanes, v_lanes)
    nodes = _grid_nodes(rows, cols, (inner, short, long_), kind, radius)

    def h(eid: str, a: str, b: str, length: float) -> Edge:
        return Edge(eid, a, b, length, h_lanes, v_h)

    def v(eid: str, a: str, b: str, length: float) -> Edge:
        return Edge(eid, a, b, length, v_lanes, v_v)

    edges = _grid_edges(rows, cols, (inner, short, long_), h, v)
    lines = straight_lines(rows, cols)
    connections = tuple(
        Connection(a, b, lane, lane)
        for line in lines
        for a, b in itertools.pairwise(line)
        for lane in range(h_lanes if a[0] in "bt" else v_lanes)
    )
    routes = {line[k]: line[k:] for line in lines for k in range(len(line))}
    return NetworkSpec(
        tuple(nodes),
        tuple(edges),
        routes,
        flow_edge_starts(rows, cols),
        float(sum(e.length for e in edges)),
        closed=False,
        connections=connections,
        internal_links=True,
        main_route=lines[0],
        extra={"rows": rows, "cols": cols},
    )


def _grid_nodes(
    rows: int, cols: int, lengths: tuple[float, float, float], kind: str, radius: float
) -> list[Node]:
    """The intersections ``center<i>`` (``kind``, junction ``radius`` m), then the ends of
    the short (inflow) and long (outflow) edges of each column and row; ``lengths``: inner,
    short and long edge lengths, m."""
    inner, short, long_ = lengths
    nodes = [Node(f"center{r * cols + c}", c * inner, r * inner, kind, radius)
             for r in range(rows) for c in range(cols)]  # fmt: skip
    top_y, right_x = (rows - 1) * inner, (cols - 1) * inner
    for c in range(cols):
        x = c * inner
        nodes += [Node(f"bot_col_short{c}", x, -short), Node(f"bot_col_long{c}", x, -long_),
                  Node(f"top_col_short{c}", x, top_y + short),
                  Node(f"top_col_long{c}", x, top_y + long_)]  # fmt: skip
    for r in range(rows):
        y = r * inner
        nodes += [Node(f"left_row_short{r}", -short, y), Node(f"left_row_long{r}", -long_, y),
                  Node(f"right_row_short{r}", right_x + short, y),
                  Node(f"right_row_long{r}", right_x + long_, y)]  # fmt: skip
    return nodes


def _grid_edges(
    rows: int,
    cols: int,
    lengths: tuple[float, float, float],
    h: Callable[[str, str, str, float], Edge],
    v: Callable[[str, str, str, float], Edge],
) -> list[Edge]:
    """The rows' edges (``h``: horizontal lanes and speed), then the columns' (``v``): both
    directions between neighbouring intersections, an inflow (short) and an outflow (long)
    edge at each end; ``lengths``: inner, short and long edge lengths, m."""
    inner, short, long_ = lengths
    edges: list[Edge] = []
    for r in range(rows):
        for c in range(1, cols):
            west, east = f"center{r * cols + c - 1}", f"center{r * cols + c}"
            edges += [h(f"bot{r}_{c}", west, east, inner), h(f"top{r}_{c}", east, west, inner)]
        first, last = f"center{r * cols}", f"center{r * cols + cols - 1}"
        edges += [h(f"bot{r}_0", f"left_row_short{r}", first, short),
                  h(f"top{r}_0", first, f"left_row_long{r}", long_),
                  h(f"top{r}_{cols}", f"right_row_short{r}", last, short),
                  h(f"bot{r}_{cols}", last, f"right_row_long{r}", long_)]  # fmt: skip
    for c in range(cols):
        for r in range(1, rows):
            south, north = f"center{(r - 1) * cols + c}", f"center{r * cols + c}"
            edges += [v(f"right{r}_{c}", south, north, inner),
                      v(f"left{r}_{c}", north, south, inner)]  # fmt: skip
        bottom, top = f"center{c}", f"center{(rows - 1) * cols + c}"
        edges += [v(f"right0_{c}", f"bot_col_short{c}", bottom, short),
                  v(f"left0_{c}", bottom, f"bot_col_long{c}", long_),
                  v(f"left{rows}_{c}", f"top_col_short{c}", top, short),
                  v(f"right{rows}_{c}", top, f"top_col_long{c}", long_)]  # fmt: skip
    return edges


def flow_edge_starts(rows: int, cols: int) -> dict[str, float]:
    """Flow's notional edge positions (``i * 50 + j * 5000`` plus 0/10/15/20 m per kind)."""
    starts: dict[str, float] = {}
    for i in range(cols + 1):
        for j in range(rows + 1):
            index, base = f"{j}_{i}", i * 50 + j * 5000
            if i != cols:
                starts[f"left{index}"], starts[f"right{index}"] = base, base + 10
            if j != rows:
                starts[f"top{index}"], starts[f"bot{index}"] = base + 15, base + 20
    return {k: float(v) for k, v in starts.items()}


class TrafficLightGridNetwork(Network):
    """Flow's ``TrafficLightGridNetwork`` (formerly ``SimpleGridScenario``).

    ``net_params.additional_params``: ``grid_array`` (``row_num``, ``col_num``,
    ``inner_length``, ``short_length``, ``long_length`` in m, which must be set, and
    ``cars_top/bot/left/right``), ``horizontal_lanes``, ``vertical_lanes``, ``speed_limit``
    (m/s, a number or per direction) and ``traffic_lights``. See :data:`ADDITIONAL_NET_PARAMS`.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "traffic_light_grid"
    #: a ring's parameters, which Flow's own grid test set-ups pass and Flow ignores
    UNUSED_FLOW_PARAMS: ClassVar[frozenset[str]] = frozenset({"length", "lanes", "resolution"})

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Defaults overlaid with ``given`` (``grid_array`` key by key), each value checked."""
        params = super().resolve_params({k: v for k, v in given.items() if k != "grid_array"})
        grid = dict(ADDITIONAL_NET_PARAMS["grid_array"])
        raw = given.get("grid_array", {})
        if not isinstance(raw, dict):
            raise ConfigError(f"expected a mapping, got {raw!r}", path="grid_array")
        for key, value in raw.items():
            if key not in grid:
                raise ConfigError(
                    f"unknown grid_array key; expected: {', '.join(grid)}",
                    path=f"grid_array.{key}",
                )
            grid[key] = value
        for key in ("inner_length", "short_length", "long_length"):
            if grid[key] is None:
                raise ConfigError("must be set (a length in m, Flow has no default)",
                                  path=f"grid_array.{key}")  # fmt: skip
        try:
            check_values(grid, _GRID_KINDS)
        except ConfigError as err:
            raise ConfigError(err.message, path=f"grid_array.{err.path}") from None
        check_values(params, {"horizontal_lanes": "count", "vertical_lanes": "count",
                              "traffic_lights": "flag"})  # fmt: skip
        speed_limits(params["speed_limit"])
        params["grid_array"] = grid
        return params

    def build_spec(self) -> NetworkSpec:
        """The grid's nodes, edges, connections and routes."""
        g = self.params["grid_array"]
        self.grid_array = g
        self.row_num, self.col_num = int(g["row_num"]), int(g["col_num"])
        self.inner_length, self.short_length, self.long_length = (
            g["inner_length"], g["short_length"], g["long_length"])  # fmt: skip
        #: Flow's (over-)count of edges, used to normalise edge numbers in observations
        self.num_edges = 4 * ((self.col_num + 1) * self.row_num + self.col_num)
        return grid_spec(self.params)

    @property
    def node_mapping(self) -> list[tuple[str, list[str]]]:
        """Flow's ``(junction, [its 4 incoming edges: from left, below, right, above])``,
        junctions sorted by name (``center0, center1, center10, ...``)."""
        rows, cols = self.row_num, self.col_num
        mapping = {
            f"center{r * cols + c}": [
                f"bot{r}_{c}",
                f"right{r}_{c}",
                f"top{r}_{c + 1}",
                f"left{r + 1}_{c}",
            ]
            for r in range(rows)
            for c in range(cols)
        }
        return sorted(mapping.items())

    def start_positions(self, rng: np.random.Generator) -> StartPositions:
        """Flow's ``custom`` placement (cars 6 m + 10 m apart at the start of the entering
        edges, lanes drawn at random) for ``spacing: custom``; the base placement otherwise."""
        if self.initial_config.spacing != "custom":
            return super().start_positions(rng)
        g, rows, cols = self.params["grid_array"], self.row_num, self.col_num
        h_lanes, v_lanes = int(self.params["horizontal_lanes"]), int(self.params["vertical_lanes"])
        groups = [(f"right0_{c}", int(g["cars_right"]), v_lanes) for c in range(cols)]
        groups += [(f"left{rows}_{c}", int(g["cars_left"]), v_lanes) for c in range(cols)]
        groups += [(f"top{r}_{cols}", int(g["cars_top"]), h_lanes) for r in range(rows)]
        groups += [(f"bot{r}_0", int(g["cars_bot"]), h_lanes) for r in range(rows)]
        edges, pos, lanes = [], [], []
        for edge, count, n_lanes in groups:
            edges += [edge] * count
            pos += [6.0 + 10.0 * k for k in range(count)]
            lanes += rng.integers(0, n_lanes, size=count).tolist()
        n = self.vehicles.num_vehicles
        if len(edges) != n:
            raise ConfigError(
                f"spacing 'custom' on the grid places cars_right/left per column and "
                f"cars_top/bot per row: {len(edges)} cars, but the vehicles number {n}",
                path="spacing",
            )
        return StartPositions(edges, pos, lanes)


#: Flow's older names.
SimpleGridScenario = TrafficLightGridNetwork
TrafficLightGridScenario = TrafficLightGridNetwork
