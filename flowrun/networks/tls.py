"""Signal programs as SUMO input: read the lights netconvert built, write ``<tlLogic>``s.

netconvert gives every ``traffic_light`` junction a default static program (program ``0``)
whose states have one character per controlled link. The programs of a
:class:`~flowrun.config.traffic_lights.TrafficLightParams` are checked against those link
counts and written to an additional file that SUMO loads after the network; a loaded program
becomes the light's active one.
"""

from __future__ import annotations

import logging
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from pathlib import Path
from xml.sax.saxutils import quoteattr

from flowrun.config.traffic_lights import Phase, TlsProgram, TrafficLightParams
from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.build import build_network
from flowrun.networks.tls_detectors import check_detector_room

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class NetLight:
    """A traffic light as built in a ``.net.xml``: its link count and default phases."""

    tls_id: str
    num_links: int
    phases: tuple[Phase, ...]


def read_net_lights(net_file: Path) -> dict[str, NetLight]:
    """The traffic lights of a SUMO network, by id (the first program of each)."""
    lights: dict[str, NetLight] = {}
    for _, elem in ET.iterparse(net_file, events=("end",)):
        if elem.tag == "tlLogic":
            tls_id = elem.get("id", "")
            if tls_id not in lights:
                phases = tuple(
                    Phase(float(p.get("duration", "0")), p.get("state", ""))
                    for p in elem.iter("phase")
                )
                n = len(phases[0].state) if phases else 0
                lights[tls_id] = NetLight(tls_id, n, phases)
        elif elem.tag in ("edge", "connection"):
            elem.clear()
    return lights


def resolve_programs(
    params: TrafficLightParams, lights: dict[str, NetLight], warn: bool = False
) -> list[TlsProgram]:
    """The programs of ``params`` for the network's ``lights``, checked.

    A program without phases takes the junction's default phases (SUMO's default program,
    run with the program's type, e.g. actuated). A static program without phases loads nothing.
    States longer than the junction's links are cut to its links, as SUMO runs them (it
    ignores the extra characters with a warning; Flow's grid example relies on it); with
    ``warn``, one warning per light names the ignored characters.

    Raises:
        ConfigError: a light on a node without one, or a state shorter than the junction's
            number of controlled links (names node, phase, expected length).
    """
    out = []
    for program in params.programs(lights):
        light = lights[program.node_id]
        if not program.phases:
            if program.tls_type == "static" and not program.offset:
                continue
            program = replace(program, phases=light.phases)
        for i, phase in enumerate(program.phases):
            if len(phase.state) < light.num_links:
                example = f"; its default program starts {light.phases[0].state!r}" \
                    if light.phases else ""  # fmt: skip
                raise ConfigError(
                    f"state {phase.state!r} has {len(phase.state)} characters but junction "
                    f"{program.node_id!r} controls {light.num_links} links (one character per "
                    f"link, in SUMO's link order{example})",
                    path=f"traffic_lights.{program.node_id}.phases[{i}].state",
                )
        out.append(_cut_to_links(program, light.num_links, warn))
    return out


def _cut_to_links(program: TlsProgram, n: int, warn: bool) -> TlsProgram:
    """``program`` with every state cut to the junction's ``n`` links (warned once)."""
    extra = [p.state[n:] for p in program.phases if len(p.state) > n]
    if not extra:
        return program
    if warn:
        log.warning(
            "traffic light %r controls %d links; its states are longer and SUMO ignores "
            "their last characters (%s)",
            program.node_id, n, ", ".join(repr(x) for x in dict.fromkeys(extra)),
        )  # fmt: skip
    phases = tuple(replace(p, state=p.state[:n]) for p in program.phases)
    return replace(program, phases=phases)


def _num(x: float) -> str:
    return repr(float(x))


def tls_additional_xml(programs: list[TlsProgram]) -> str:
    """The ``<additional>`` text holding one ``<tlLogic>`` per program."""
    rows = ["<additional>"]
    for p in programs:
        rows.append(
            f"    <tlLogic id={quoteattr(p.node_id)} type={quoteattr(p.tls_type)} "
            f"programID={quoteattr(p.program_id)} offset={quoteattr(_num(p.offset))}>"
        )
        for key, value in p.params:
            rows.append(f"        <param key={quoteattr(key)} value={quoteattr(value)}/>")
        for ph in p.phases:
            extra = "" if ph.min_dur is None else f' minDur="{_num(ph.min_dur)}"'
            extra += "" if ph.max_dur is None else f' maxDur="{_num(ph.max_dur)}"'
            rows.append(
                f'        <phase duration="{_num(ph.duration)}" state={quoteattr(ph.state)}'
                f"{extra}/>"
            )
        rows.append("    </tlLogic>")
    rows.append("</additional>")
    return "\n".join(rows) + "\n"


def write_tls_file(params: TrafficLightParams, net_file: Path, out_dir: Path) -> Path | None:
    """Check the programs of ``params`` against ``net_file`` and write them next to it.

    Returns:
        The additional file to load, or ``None`` when there is nothing to load.

    Raises:
        ConfigError: see :func:`resolve_programs`.
    """
    if not params.get_properties() and not params.baseline:
        return None
    programs = resolve_programs(params, read_net_lights(net_file))
    if not programs:
        return None
    check_detector_room(programs, net_file)
    path = out_dir / f"{net_file.name.removesuffix('.net.xml')}.tls.add.xml"
    path.write_text(tls_additional_xml(programs))
    return path


def check_programs(network: Network, params: TrafficLightParams) -> None:
    """Build ``network`` with netconvert (in a temporary folder) and check ``params`` on it.

    Raises:
        ConfigError: see :func:`resolve_programs`; an actuated program without room
            for its detectors (:mod:`flowrun.networks.tls_detectors`).
        SimulationError: netconvert failed.
    """
    with tempfile.TemporaryDirectory(prefix="flowrun-tls-") as tmp:
        net_file = build_network(network.spec, Path(tmp), name=network.network_type or "network")
        programs = resolve_programs(params, read_net_lights(net_file), warn=True)
        check_detector_room(programs, net_file)
