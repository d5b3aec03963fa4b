"""The vehicle types and vehicles of Flow's template dict ``{net, rou, vtype}``, as Flow reads them.

What Flow does (``flow/networks/base.py``: ``_vehicle_type``, ``_get_cf_params``,
``_get_lc_params``, ``_vehicle_infos``; ``flow/core/kernel/vehicle/traci.py``: ``update(reset)``):

- Each ``<vType>`` of the ``vtype`` file (only those inside ``<vTypeDistribution>`` elements
  when the file has any) becomes a vehicle type of the network's ``VehicleParams``:
  ``add(id, num_vehicles=0, car_following_params=SumoCarFollowingParams(speed_mode=
  "all_checks", accel, decel, sigma, min_gap, max_speed, speed_dev), lane_change_params=
  SumoLaneChangeParams(lane_change_mode=1621))`` with SUMO's own controllers
  (``SimCarFollowingController``, ``SimLaneChangeController``). Only those six attributes are
  read (each one is required); ``tau``, ``speedFactor``, ``impatience``, ``carFollowModel``,
  ``length`` and the lane-change attributes keep Flow's defaults (1.0, 1.0, 0.5, IDM, 5 m,
  LC2013 with 1.0 eagerness).
- Neither file is given to SUMO: the types reach SUMO as every vehicle type does, and each
  ``<vehicle>`` of the ``rou`` files is added at every reset on its own route (Flow's
  ``route<id>_0``), departing at its ``depart`` plus the two steps of the reset, with its
  ``departPos`` and ``departSpeed`` (the file's ``departLane`` is not read: ``first``). Its
  type's controllers and modes drive it from its first step, like any departing car.

flowrun's choices where Flow fails or is silent: a user's vehicle type with the id of a vType
keeps its own settings (in Flow the id would reach SUMO twice and SUMO would refuse it); the
``vtype`` file is read also without a ``rou`` file; a ``rou`` file still goes to SUMO for what
Flow does not read from it (its ``<flow>``s, trips, own ``<vType>``s), as a copy without the
vehicles flowrun adds and without the vTypes a vehicle type already defines; a vehicle may name
a ``<route>`` by id instead of holding one; ``type``, ``departPos`` and ``departSpeed`` default
to SUMO's (``DEFAULT_VEHTYPE``, driven by SUMO; ``base``; ``0``).
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from flowrun.config.params import VehicleParams
from flowrun.config.vtype import SumoCarFollowingParams, SumoLaneChangeParams
from flowrun.errors import ConfigError
from flowrun.networks.spec import NetworkSpec, TemplateVehicle
from flowrun.networks.template_read import file_names, read_xml
from flowrun.suggest import did_you_mean

#: vType attribute -> ``SumoCarFollowingParams`` field: what Flow reads from every vType
VTYPE_ATTRIBUTES: dict[str, str] = {
    "accel": "accel",
    "decel": "decel",
    "sigma": "sigma",
    "minGap": "min_gap",
    "maxSpeed": "max_speed",
    "speedDev": "speed_dev",
}
#: Flow's modes of a template's vehicle types: ``all_checks`` and ``strategic``
SPEED_MODE, LANE_CHANGE_MODE = 31, 1621
#: SUMO's type of a vehicle that names none
SUMO_DEFAULT_TYPE = "DEFAULT_VEHTYPE"


def read_vtypes(path: str) -> dict[str, tuple[SumoCarFollowingParams, SumoLaneChangeParams]]:
    """The vehicle types of a ``vtype`` file with Flow's parameters (module docstring).

    Raises:
        ConfigError: the file is not XML, a vType has no id, lacks one of the six attributes
            Flow reads, or one of them is not a number.
    """
    root = read_xml(path, "vtype")
    parents = root.findall("vTypeDistribution") or [root]  # Flow's rule for LuST's files
    out: dict[str, tuple[SumoCarFollowingParams, SumoLaneChangeParams]] = {}
    for parent in parents:
        for i, element in enumerate(parent.findall("vType")):
            type_id = element.get("id")
            if not type_id:
                raise ConfigError(
                    f"vType number {i + 1} in {path!r} has no id; give every vType an id",
                    path="template.vtype",
                )
            cf = SumoCarFollowingParams(speed_mode=SPEED_MODE)  # Flow's defaults, then ...
            for attr, name in VTYPE_ATTRIBUTES.items():  # ... the six it reads
                text = element.get(attr)
                where = f"vType '{type_id}' in {path!r}"
                if text is None:
                    raise ConfigError(
                        f"{where} has no {attr}; Flow reads {', '.join(VTYPE_ATTRIBUTES)} "
                        "from every vType: add it", path="template.vtype",
                    )  # fmt: skip
                try:
                    setattr(cf, name, float(text))
                except ValueError:
                    raise ConfigError(f"{where}: {attr}={text!r} is not a number",
                                      path="template.vtype") from None  # fmt: skip
            out[type_id] = (cf, SumoLaneChangeParams(lane_change_mode=LANE_CHANGE_MODE))
    return out


def read_vehicles(files: Iterable[str]) -> tuple[tuple[TemplateVehicle, ...], set[str]]:
    """The ``<vehicle>``s of ``rou`` files, and the ids of the files' own ``<vType>``s.

    Raises:
        ConfigError: a file is not XML; a vehicle has no id, a ``depart`` that is not a
            number of seconds, no route, or an id used twice.
    """
    roots = [(name, read_xml(name, "rou")) for name in files]
    routes = {r.get("id", ""): r.get("edges", "") for _, root in roots for r in root.iter("route")}
    own_types = {t.get("id", "") for _, root in roots for t in root.iter("vType")}
    out: dict[str, TemplateVehicle] = {}
    for name, root in roots:
        for element in root.findall("vehicle"):
            vid, where = element.get("id", ""), f"vehicle '{element.get('id', '')}' in {name!r}"
            if not vid or vid in out:
                raise ConfigError(f"{where}: a vehicle needs an id of its own",
                                  path="template.rou")  # fmt: skip
            inline = element.find("route")
            edges = inline.get("edges") if inline is not None else routes.get(
                element.get("route", ""))  # fmt: skip
            if not edges:
                raise ConfigError(f"{where} has no route: give it <route edges=...> or "
                                  "route=\"<id of a <route>>\"", path="template.rou")  # fmt: skip
            type_id = element.get("type", SUMO_DEFAULT_TYPE)
            try:
                depart = float(element.get("depart", ""))
            except ValueError:
                raise ConfigError(
                    f"{where}: depart={element.get('depart')!r} is not a time in seconds",
                    path="template.rou",
                ) from None
            out[vid] = TemplateVehicle(
                vid, type_id, tuple(edges.split()), depart,
                element.get("departPos", "base"), element.get("departSpeed", "0"),
            )  # fmt: skip
    return tuple(out.values()), own_types


def apply_template(
    template: Mapping[str, Any], vehicles: VehicleParams, spec: NetworkSpec
) -> tuple[VehicleParams, NetworkSpec]:
    """The network's vehicle types and spec with a template dict's vTypes and vehicles.

    Returns a new ``VehicleParams`` (``vehicles``' groups, then one empty group per vType
    whose id no group has) and ``spec`` with the ``rou`` vehicles as its departures.

    Raises:
        ConfigError: see :func:`read_vtypes`, :func:`read_vehicles`; a vehicle of a type
            defined nowhere, on an edge the network lacks, or with the id of a vehicle of
            ``vehicles``.
    """
    out = VehicleParams(list(vehicles.groups))
    for vtype in file_names(template.get("vtype")):
        for type_id, (cf, lc) in read_vtypes(vtype).items():
            if type_id not in out.type_names:  # the user's own type of that id stays
                out.add(type_id, num_vehicles=0, car_following_params=cf,
                        lane_change_params=lc)  # fmt: skip
    departures, own_types = read_vehicles(file_names(template.get("rou")))
    known = set(out.type_names) | own_types | {SUMO_DEFAULT_TYPE}
    edges, taken = {e.id for e in spec.edges}, set(out.ids)
    for d in departures:
        where = f"template vehicle '{d.id}'"
        if d.type not in known:
            raise ConfigError(
                f"{where} is of type '{d.type}', which neither the vtype file nor the "
                f"vehicles define{did_you_mean(d.type, known)}; known types: "
                f"{', '.join(sorted(known)) or '(none)'}", path="template.rou",
            )  # fmt: skip
        if unknown := [e for e in d.route if e not in edges]:
            raise ConfigError(
                f"{where} drives on '{unknown[0]}', which the network has not"
                f"{did_you_mean(unknown[0], edges)}", path="template.rou",
            )  # fmt: skip
        if d.id in taken:
            raise ConfigError(f"{where} has the id of a vehicle of the vehicle types; "
                              "rename one of them", path="template.rou")  # fmt: skip
    return out, dataclasses.replace(spec, departures=departures)


def sumo_route_files(
    files: Iterable[str], defined_types: set[str], added: set[str], out_dir: Path
) -> tuple[Path, ...]:
    """The route files to give SUMO: each of ``files``, or a copy in ``out_dir`` without the
    vehicles flowrun adds (``added``) and the vTypes flowrun defines (``defined_types``), so
    that SUMO sees no id twice."""
    out = []
    for i, name in enumerate(files):
        tree = ET.parse(name)
        root = tree.getroot()
        drop = [e for e in root if (e.tag == "vehicle" and e.get("id") in added)
                or (e.tag == "vType" and e.get("id") in defined_types)]  # fmt: skip
        if not drop:
            out.append(Path(name))
            continue
        for element in drop:
            root.remove(element)
        copy = out_dir / f"template_{i}.rou.xml"
        tree.write(copy, encoding="unicode")
        out.append(copy)
    return tuple(out)
