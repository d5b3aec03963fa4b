"""A user's own road: a SUMO ``.net.xml`` (``NetParams(template=...)``) or an OpenStreetMap
file converted by netconvert (``NetParams(osm_path=...)``).

The network file is used as is; its edges (ids, lanes, lengths, speed limits) are read with
``xml.etree`` and laid end to end in file order for absolute positions. Routes come from the
``routes`` parameter (YAML ``network.routes``) or a subclass's Flow-style
``specify_routes(net_params)``: start edge -> list of edges, or start edge -> list of
``(edges, probability)`` choices. Without routes, a car's route is its start edge.
"""

from __future__ import annotations

import hashlib
import itertools
import os
import subprocess
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

from flowrun.errors import ConfigError
from flowrun.networks.base import Edge, Network, NetworkSpec, Node, RouteChoice
from flowrun.networks.build import check_net_file, sumo_binary
from flowrun.suggest import did_you_mean

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # start edge -> [edges] or [[edges, probability], ...]; None: each car drives its edge
    "routes": None,
}


def read_net(path: Path) -> tuple[tuple[Node, ...], tuple[Edge, ...], set[tuple[str, str]]]:
    """Junctions, non-internal edges and edge-to-edge connections of a SUMO network file."""
    root = ET.parse(path).getroot()
    nodes = tuple(
        Node(j.get("id", ""), float(j.get("x", 0)), float(j.get("y", 0)), j.get("type", ""))
        for j in root.iter("junction")
        if j.get("type") != "internal"
    )
    edges = []
    for e in root.iter("edge"):
        lanes = e.findall("lane")
        if e.get("function") == "internal" or not lanes:
            continue
        edges.append(
            Edge(
                e.get("id", ""),
                e.get("from", ""),
                e.get("to", ""),
                float(lanes[0].get("length", 0)),
                len(lanes),
                float(lanes[0].get("speed", 0)),
                priority=int(e.get("priority", -1)),
            )
        )
    links = {(c.get("from", ""), c.get("to", "")) for c in root.iter("connection")}
    return nodes, tuple(edges), links


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


def file_names(value: Any) -> list[str]:
    """A template entry as a list of file names (Flow takes one name or a list)."""
    if value is None:
        return []
    return [str(value)] if isinstance(value, str | os.PathLike) else [str(v) for v in value]


def read_xml(path: str, key: str) -> ET.Element:
    """The root element of a template's ``key`` file (``rou``, ``vtype``).

    Raises:
        ConfigError: the file is not readable XML, at ``template.<key>``.
    """
    try:
        return ET.parse(path).getroot()
    except (OSError, ET.ParseError) as err:
        raise ConfigError(
            f"cannot read {key} file {path!r} as XML ({err}); give a SUMO {key} file",
            path=f"template.{key}",
        ) from None


def template_files(template: Any) -> tuple[Path, tuple[str, ...]]:
    """The net file and the route files of Flow's ``template`` (a path or a dict).

    The ``vtype`` file is checked too but not returned: its vTypes reach SUMO as vehicle
    types of the network (:mod:`flowrun.networks.template_demand`).
    """
    if isinstance(template, Mapping):
        if "net" not in template:
            raise ConfigError("a template dict needs a 'net' file (and optionally 'rou', "
                              "'vtype')", path="template")  # fmt: skip
        extra: list[str] = []
        for key in ("rou", "vtype"):
            for name in file_names(template.get(key)):
                if not Path(name).is_file():
                    raise ConfigError(f"{key} file {str(name)!r} not found", path="template")
                if key == "rou":
                    extra.append(str(name))
        return check_net_file(template["net"]), tuple(extra)
    return check_net_file(template), ()


def rou_routes(files: Any) -> dict[str, list[str]]:
    """The routes of route files as Flow reads a template's ``rou``: ``{id: [edges]}`` for
    each ``<route>`` and, under the vehicle's id, each route written inside a ``<vehicle>``.

    Raises:
        ConfigError: a file is not readable XML.
    """
    out: dict[str, list[str]] = {}
    for name in file_names(files):
        root = read_xml(name, "rou")
        for vehicle in root.iter("vehicle"):
            route = vehicle.find("route")
            if route is not None and "edges" in route.attrib:
                out[vehicle.attrib.get("id", "")] = route.attrib["edges"].split()
        for route in root.findall("route"):
            if "id" in route.attrib:
                out[route.attrib["id"]] = route.attrib.get("edges", "").split()
    return out


def osm_cache_dir() -> Path:
    """Where converted OSM networks are kept (content-addressed, never overwritten)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "flowrun" / "osm"


def convert_osm(osm_path: str | Path, out_dir: Path | None = None) -> Path:
    """Convert an OpenStreetMap file with netconvert (passenger roads); cached by content.

    Raises:
        ConfigError: the file is missing or netconvert rejects it (its errors quoted).
    """
    osm = Path(osm_path)
    if not osm.is_file():
        raise ConfigError(f"OSM file {str(osm)!r} not found", path="osm_path")
    out_dir = out_dir or osm_cache_dir()
    out_dir.mkdir(parents=True, exist_ok=True)
    digest = hashlib.sha1(osm.read_bytes()).hexdigest()[:16]
    net_file = out_dir / f"{osm.stem}-{digest}.net.xml"
    if net_file.exists():
        return net_file
    tmp = out_dir / f"{osm.stem}-{digest}.{os.getpid()}.tmp.xml"
    cmd = [
        sumo_binary("netconvert"), "--osm-files", str(osm), "--output-file", str(tmp),
        "--keep-edges.by-vclass", "passenger", "--no-turnarounds", "true",
        "--precision", "6", "--no-warnings", "true",
    ]  # fmt: skip
    import sumo  # the eclipse-sumo wheel: its type maps and schemas

    env = {**os.environ, "SUMO_HOME": str(sumo.SUMO_HOME)}
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    if proc.returncode != 0 or not tmp.exists():
        lines = (proc.stderr + proc.stdout).splitlines()
        errors = [ln.strip() for ln in lines if ln.startswith(("Error", " In file", " At"))]
        detail = " ".join(errors) or (proc.stderr or proc.stdout).strip()
        raise ConfigError(f"netconvert could not import OSM file {str(osm)!r}: {detail}",
                          path="osm_path")  # fmt: skip
    tmp.replace(net_file)
    return net_file


class TemplateNetwork(Network):
    """A network read from a ``.net.xml`` (Flow's ``NetParams(template=...)``) or an OSM file.

    ``net_params.template``: the ``.net.xml`` path, or Flow's dict ``{net, rou, vtype}``;
    ``net_params.osm_path``: an OpenStreetMap file. ``additional_params``: ``routes``.
    Subclasses may define Flow's ``specify_routes(net_params)`` instead.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "template"
    LIST_NOTE: ClassVar[str] = "with template: file.net.xml or osm_path: file.osm"

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Merge with defaults; ``routes`` must be a mapping (checked against the file later)."""
        params = super().resolve_params(given)
        if params["routes"] is not None and not isinstance(params["routes"], Mapping):
            raise ConfigError(
                "expected a mapping start edge -> [edges] or [[edges, probability], ...], "
                f"got {params['routes']!r}",
                path="routes",
            )
        return params

    def build_spec(self) -> NetworkSpec:
        """Read the network file's edges and the routes."""
        template: Any = self.net_params.template
        if template is not None:
            net_file, extra = template_files(template)
        elif self.net_params.osm_path is not None:
            net_file, extra = convert_osm(self.net_params.osm_path), ()
        else:
            raise ConfigError(
                "a template network needs `template: path/to/net.net.xml` or "
                "`osm_path: path/to/map.osm`",
                path="template",
            )
        nodes, edges, links = read_net(net_file)
        given = self.specify_routes(self.net_params)
        ids = {e.id for e in edges}
        routes, choices = parse_routes(given, ids, links, str(net_file))
        if not given:
            routes = {e.id: (e.id,) for e in edges}
        starts, total = {}, 0.0
        for e in edges:
            starts[e.id] = total
            total += e.length
        return NetworkSpec(
            nodes, edges, routes, starts, total, closed=False, route_choices=choices,
            internal_links=True, net_file=str(net_file), extra_files=extra,
        )  # fmt: skip

    def specify_routes(self, net_params: Any) -> Mapping[str, Any]:
        """Flow's hook: start edge -> route (or route choices); default the ``routes`` param."""
        return self.params.get("routes") or {}

