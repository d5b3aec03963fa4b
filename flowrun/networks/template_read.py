"""Reading a user's road from files: a SUMO ``.net.xml`` (``NetParams(template=...)``), Flow's
template dict ``{net, rou, vtype}``, or an OpenStreetMap file converted by netconvert
(``NetParams(osm_path=...)``), into a :class:`~flowrun.networks.spec.NetworkSpec`.

The network file is used as is; its edges (ids, lanes, lengths, speed limits) are read with
``xml.etree`` and laid end to end in file order for absolute positions.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from flowrun.errors import ConfigError
from flowrun.networks.build import check_net_file, sumo_binary
from flowrun.networks.route_forms import parse_routes
from flowrun.networks.spec import Edge, NetworkSpec, Node


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


def template_spec(net_params: Any, given_routes: Mapping[str, Any]) -> NetworkSpec:
    """The spec of a road read from ``net_params.template`` (a ``.net.xml`` or Flow's
    ``{net, rou, vtype}``) or ``net_params.osm_path``: the file's edges laid end to end in
    file order, and ``given_routes`` (Flow's ``specify_routes`` forms; each edge alone when
    empty).

    Raises:
        ConfigError: neither is given, a file is missing or unreadable, or a route is wrong.
    """
    template: Any = net_params.template
    if template is not None:
        net_file, extra = template_files(template)
    elif net_params.osm_path is not None:
        net_file, extra = convert_osm(net_params.osm_path), ()
    else:
        raise ConfigError(
            "a template network needs `template: path/to/net.net.xml` or "
            "`osm_path: path/to/map.osm`",
            path="template",
        )
    nodes, edges, links = read_net(net_file)
    ids = {e.id for e in edges}
    routes, choices = parse_routes(given_routes, ids, links, str(net_file))
    if not given_routes:
        routes = {e.id: (e.id,) for e in edges}
    starts, total = {}, 0.0
    for e in edges:
        starts[e.id] = total
        total += e.length
    return NetworkSpec(
        nodes, edges, routes, starts, total, closed=False, route_choices=choices,
        internal_links=True, net_file=str(net_file), extra_files=extra,
    )  # fmt: skip
