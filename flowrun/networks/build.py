"""Write a :class:`NetworkSpec` as SUMO XML and convert it with ``netconvert``.

netconvert comes from the ``eclipse-sumo`` wheel; its own message is shown on failure.
Converted networks are cached per output folder and spec, so a ring that reappears with the
same parameters is not rebuilt. A spec that names an existing ``.net.xml`` (a template) is
checked and used as is.
"""

from __future__ import annotations

import hashlib
import signal
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path
from xml.sax.saxutils import quoteattr

from flowrun.errors import ConfigError, SimulationError
from flowrun.networks.spec import NetworkSpec


def sumo_binary(name: str) -> str:
    """Path of a SUMO tool (``sumo``, ``sumo-gui``, ``netconvert``) from the eclipse-sumo wheel."""
    try:
        import sumo  # the eclipse-sumo wheel
    except ImportError as err:  # pragma: no cover - a broken install
        raise SimulationError(
            "the eclipse-sumo package is not installed; run `pip install eclipse-sumo`"
        ) from err
    path = Path(sumo.SUMO_HOME) / "bin" / name
    if not path.exists():
        raise SimulationError(f"SUMO tool '{name}' not found at {path}; reinstall eclipse-sumo")
    return str(path)


def nodes_xml(spec: NetworkSpec) -> str:
    """The ``.nod.xml`` text of a spec."""
    rows = []
    for n in spec.nodes:
        radius = "" if n.radius is None else f' radius="{n.radius:.6f}"'
        rows.append(
            f'    <node id={quoteattr(n.id)} x="{n.x:.6f}" y="{n.y:.6f}" '
            f"type={quoteattr(n.type)}{radius}/>"
        )
    return "<nodes>\n" + "\n".join(rows) + "\n</nodes>\n"


def edges_xml(spec: NetworkSpec) -> str:
    """The ``.edg.xml`` text of a spec."""
    rows = []
    for e in spec.edges:
        shape = " ".join(f"{x:.6f},{y:.6f}" for x, y in e.shape)
        shape_attr = f' shape="{shape}"' if shape else ""
        spread = "" if e.spread_type == "right" else f" spreadType={quoteattr(e.spread_type)}"
        rows.append(
            f"    <edge id={quoteattr(e.id)} from={quoteattr(e.from_node)} "
            f'to={quoteattr(e.to_node)} numLanes="{e.lanes}" speed="{e.speed:.6f}" '
            f'length="{e.length:.9f}" priority="{e.priority}"{shape_attr}{spread}/>'
        )
    return "<edges>\n" + "\n".join(rows) + "\n</edges>\n"


def connections_xml(spec: NetworkSpec) -> str:
    """The ``.con.xml`` text of a spec (empty when netconvert may choose the connections)."""
    if not spec.connections:
        return ""
    rows = [
        f"    <connection from={quoteattr(c.from_edge)} to={quoteattr(c.to_edge)} "
        f'fromLane="{c.from_lane}" toLane="{c.to_lane}"/>'
        for c in spec.connections
    ]
    return "<connections>\n" + "\n".join(rows) + "\n</connections>\n"


def check_net_file(path: str | Path, what: str = "template") -> Path:
    """``path`` if it is a readable SUMO network (root element ``<net>``).

    Args:
        path: the ``.net.xml`` file.
        what: the config key that named it (the error's ``path``).

    Raises:
        ConfigError: the file is missing, is not XML, or is not a SUMO network.
    """
    file = Path(path)
    if not file.is_file():
        raise ConfigError(
            f"SUMO network file {str(file)!r} not found; give the path of an existing .net.xml",
            path=what,
        )
    try:
        root_tag = next(ET.iterparse(file, events=("start",)))[1].tag
    except (ET.ParseError, StopIteration) as err:
        raise ConfigError(
            f"{str(file)!r} is not a SUMO network (not readable as XML: {err})", path=what
        ) from None
    if root_tag != "net":
        raise ConfigError(
            f"{str(file)!r} is not a SUMO network: its root element is <{root_tag}>, "
            "expected <net> (a .net.xml written by netconvert or netedit)",
            path=what,
        )
    return file


def netconvert_command(spec: NetworkSpec, files: dict[str, Path], output: Path) -> list[str]:
    """The netconvert command line for ``spec`` (its XML already written to ``files``)."""
    cmd = [sumo_binary("netconvert"), "--node-files", str(files["nod"])]
    cmd += ["--edge-files", str(files["edg"])]
    if "con" in files:
        cmd += ["--connection-files", str(files["con"])]
    cmd += ["--output-file", str(output)]
    if not spec.internal_links:
        cmd += ["--no-internal-links", "true"]
    return [
        *cmd,
        "--no-turnarounds",
        "true",
        "--offset.disable-normalization",
        "true",
        # lengths to 1e-6 m (default 0.01 m): on a 230.3 m ring a lap would otherwise be
        # 230.32 m in SUMO and ring positions would drift from SUMO's by 0.02 m per lap
        "--precision",
        "6",
        "--no-warnings",
        "true",
    ]


def build_network(spec: NetworkSpec, out_dir: Path, name: str = "network") -> Path:
    """Convert ``spec`` into ``out_dir/<name>-<hash>.net.xml`` and return its path.

    A spec with ``net_file`` (a template) returns that file, checked, without converting.

    Raises:
        ConfigError: the template file is missing or not a SUMO network.
        SimulationError: netconvert failed; the message holds netconvert's own output.
    """
    if spec.net_file is not None:
        return check_net_file(spec.net_file)
    out_dir.mkdir(parents=True, exist_ok=True)
    texts = {"nod": nodes_xml(spec), "edg": edges_xml(spec), "con": connections_xml(spec)}
    flags = f"internal_links={spec.internal_links}"
    digest = hashlib.sha1((texts["nod"] + texts["edg"] + texts["con"] + flags).encode())
    stem = f"{name}-{digest.hexdigest()[:12]}"
    net_file = out_dir / f"{stem}.net.xml"
    if net_file.exists():
        return net_file
    files: dict[str, Path] = {}
    for kind, text in texts.items():
        if text:
            files[kind] = out_dir / f"{stem}.{kind}.xml"
            files[kind].write_text(text)
    tmp = net_file.with_suffix(".tmp.xml")
    proc = subprocess.run(
        netconvert_command(spec, files, tmp), capture_output=True, text=True, check=False
    )
    if proc.returncode != 0 or not tmp.exists():
        message = (proc.stderr or proc.stdout).strip()
        if proc.returncode < 0:  # killed: Ctrl-C or SIGTERM to the process group, the OOM killer
            message = f"stopped by {signal.Signals(-proc.returncode).name}"
        raise SimulationError(f"netconvert failed on {files['edg']}: {message}")
    tmp.replace(net_file)
    return net_file
