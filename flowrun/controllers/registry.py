"""Controller names a config may use, and turning a name plus parameters into an object.

A name is a registered short name (``IDM``), a class name (``IDMController``), an alias, or
an import path ``package.module:Class`` for a user's own controller class (which must derive
from :class:`AccelerationController`, :class:`Router` or :class:`LaneChangeController`).
The table is fixed at import time; nothing registers at run time.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Mapping
from typing import Any, Literal

from flowrun.controllers.base import AccelerationController
from flowrun.controllers.car_following import (
    BandoFTLController,
    BCMController,
    CFMController,
    GippsController,
    IDMController,
    LACController,
    LinearOVM,
    OVMController,
)
from flowrun.controllers.i210_router import I210Router
from flowrun.controllers.lane_change import (
    LaneChangeController,
    SimLaneChangeController,
    StaticLaneChanger,
)
from flowrun.controllers.minicity_router import MinicityRouter
from flowrun.controllers.nonlocal_follower_stopper import NonLocalFollowerStopper
from flowrun.controllers.params import Param, parameters
from flowrun.controllers.per_vehicle import PerVehicleGroup
from flowrun.controllers.rl import RLController, SimCarFollowingController
from flowrun.controllers.routing import ContinuousRouter, GridRouter, Router
from flowrun.controllers.velocity import FollowerStopper, PISaturation
from flowrun.errors import BadValueError, ConfigError
from flowrun.suggest import did_you_mean, unknown_name

ControllerKind = Literal["acceleration", "routing", "lane_change"]

#: Constructor arguments that exist for Flow's per-vehicle construction
#: (``IDMController("human_0", car_following_params=...)``); a config never sets them.
FLOW_ONLY_PARAMS = frozenset(
    {"veh_id", "car_following_params", "router_params", "lane_change_params", "display_warnings"}
)

_BASES: tuple[tuple[ControllerKind, type], ...] = (
    ("acceleration", AccelerationController),
    ("routing", Router),
    ("lane_change", LaneChangeController),
)

_BUILTIN: tuple[type, ...] = (
    IDMController,
    OVMController,
    LinearOVM,
    BCMController,
    CFMController,
    BandoFTLController,
    GippsController,
    LACController,
    FollowerStopper,
    NonLocalFollowerStopper,
    PISaturation,
    SimCarFollowingController,
    RLController,
    ContinuousRouter,
    GridRouter,
    MinicityRouter,
    I210Router,
    SimLaneChangeController,
    StaticLaneChanger,
)


def _names_of(cls: type) -> tuple[str, ...]:
    names = [getattr(cls, "registered_name", ""), cls.__name__, *getattr(cls, "aliases", ())]
    return tuple(dict.fromkeys(n for n in names if n))


_LOOKUP: dict[str, type] = {name: cls for cls in _BUILTIN for name in _names_of(cls)}


def controller_kind(cls: type) -> ControllerKind:
    """``"acceleration"``, ``"routing"`` or ``"lane_change"`` for a controller class.

    Raises:
        ConfigError: if ``cls`` derives from none of the controller base classes.
    """
    if isinstance(cls, type):
        for kind, base in _BASES:
            if issubclass(cls, base):
                return kind
    raise ConfigError(
        f"{getattr(cls, '__qualname__', repr(cls))} is not a controller; a controller class "
        "must derive from flowrun.controllers.AccelerationController, Router or "
        "LaneChangeController"
    )


def controller_names(kind: ControllerKind | None = None) -> list[str]:
    """Registered names of the built-in controllers (of one kind, if given), in table order."""
    return [
        str(getattr(cls, "registered_name", cls.__name__))
        for cls in _BUILTIN
        if kind is None or controller_kind(cls) == kind
    ]


def controller_parameters(cls: type) -> tuple[Param, ...]:
    """The parameters a config may give controller ``cls`` (Flow's per-vehicle arguments,
    :data:`FLOW_ONLY_PARAMS`, left out), in constructor order."""
    return tuple(p for p in parameters(cls) if p.name not in FLOW_ONLY_PARAMS)


def controller_lines() -> list[str]:
    """``flowrun list controllers``: per built-in controller, a line with its name, class and
    kind, then one indented line per parameter: name, default, unit, bounds and meaning."""
    lines = []
    for cls in _BUILTIN:
        name = str(getattr(cls, "registered_name", cls.__name__))
        lines.append(f"{name}  ({cls.__name__}, {controller_kind(cls).replace('_', '-')})")
        for p in controller_parameters(cls):
            unit = f" {p.unit}" if p.unit and p.default is not None else ""
            bounds = f", {p.bounds}" if p.bounds else ""
            lines.append(f"    {p.name} = {_shown(p.default)}{unit}{bounds}: {p.doc}")
    return lines


def _shown(value: Any) -> str:
    """A default as a config would write it."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _article(kind: ControllerKind) -> str:
    text = kind.replace("_", "-")
    return f"an {text}" if text[0] in "aeiou" else f"a {text}"


def _import_path(name: str) -> type[Any]:
    module_name, _, attr = name.partition(":")
    if not module_name or not attr:
        raise ConfigError(f"bad controller import path '{name}'; expected 'package.module:Class'")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ConfigError(
            f"cannot import module '{module_name}' for controller '{name}': {exc}; put it "
            "next to the config file, install it, or add its folder to PYTHONPATH"
        ) from exc
    obj: Any = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            public = [n for n in dir(obj) if not n.startswith("_")]
            raise ConfigError(
                f"module '{module_name}' has no attribute '{attr}'{did_you_mean(part, public)}"
            )
        obj = getattr(obj, part)
    if not isinstance(obj, type):
        raise ConfigError(f"'{name}' is not a class (got {type(obj).__name__})")
    controller_kind(obj)
    return obj


def resolve_controller(name: str, kind: ControllerKind | None = None) -> type[Any]:
    """The controller class a config name stands for.

    Args:
        name: registered name (``IDM``), class name (``IDMController``), alias, or import
            path ``package.module:Class``.
        kind: when given, the class must be of this kind.

    Raises:
        ConfigError: unknown name (with a did-you-mean), failed import, wrong kind.
    """
    if not isinstance(name, str) or not name:
        raise ConfigError(f"a controller type must be a non-empty name, got {name!r}")
    if ":" in name:
        cls = _import_path(name)
    elif name in _LOOKUP:
        cls = _LOOKUP[name]
    else:
        pool = [n for n, c in _LOOKUP.items() if kind is None or controller_kind(c) == kind]
        what = f"{kind.replace('_', '-')} controller" if kind else "controller"
        raise ConfigError(
            unknown_name(what, name, pool) + ", or an import path 'package.module:Class'"
        )
    found = controller_kind(cls)
    if kind is not None and found != kind:
        raise ConfigError(
            f"'{name}' is {_article(found)} controller, but {_article(kind)} controller "
            "is expected here"
        )
    return cls


def build_controller(
    name: str | type,
    params: Mapping[str, Any] | None = None,
    kind: ControllerKind | None = None,
    *,
    veh_id: str | None = None,
    car_following_params: Any = None,
) -> Any:
    """Instantiate the controller ``name`` with keyword ``params``.

    ``name`` may also be the class itself (Flow's ``(MyController, {...})``).
    ``veh_id`` and ``car_following_params`` are passed on when the constructor takes them
    and they are given (or the constructor requires them, as a Flow-style user class does).

    A Flow-style acceleration class (``get_accel(self, env)``, see
    :mod:`flowrun.controllers.per_vehicle`) gives a :class:`PerVehicleGroup` that makes one
    object per vehicle; a Flow-style router gets ``params`` as Flow's ``router_params``.

    Raises:
        ConfigError: unknown controller, unknown parameter (with a did-you-mean against the
            constructor's parameters), or a value the constructor refuses. When the error is
            about one parameter, ``ConfigError.path`` is that parameter's name.
    """
    if isinstance(name, type):
        cls: type[Any] = name
        found = controller_kind(cls)
        if kind is not None and found != kind:
            raise ConfigError(
                f"{cls.__name__} is {_article(found)} controller, but {_article(kind)} "
                "controller is expected here"
            )
    else:
        cls = resolve_controller(name, kind)
    params = dict(params or {})
    if issubclass(cls, Router) and cls.per_vehicle:  # Flow: Cls(veh_id, router_params=params)
        return _construct(cls, {"veh_id": veh_id, "router_params": params})
    signature = inspect.signature(cls)
    accepted = [
        p.name
        for p in signature.parameters.values()
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.name not in FLOW_ONLY_PARAMS
    ]
    takes_any = any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values())
    if not takes_any:
        for key in params:
            if key not in accepted:
                expected = ", ".join(accepted) if accepted else "no parameters"
                raise ConfigError(
                    f"unknown parameter '{key}' for {cls.__name__}"
                    f"{did_you_mean(str(key), accepted)}; expected: {expected}",
                    path=str(key),
                )
    if issubclass(cls, AccelerationController) and cls.per_vehicle:
        return PerVehicleGroup(cls, params, car_following_params)
    for extra, value in (("veh_id", veh_id), ("car_following_params", car_following_params)):
        p = signature.parameters.get(extra)
        if p is not None and (value is not None or p.default is p.empty):
            params[extra] = value
    return _construct(cls, params)


def _construct(cls: type[Any], params: dict[str, Any]) -> Any:
    """``cls(**params)``, a refused value reported as a :class:`ConfigError`."""
    try:
        return cls(**params)
    except (ValueError, TypeError) as exc:
        detail = str(exc).removeprefix(f"{cls.__name__}: ")
        error = BadValueError if isinstance(exc, ValueError) else ConfigError
        raise error(
            f"bad parameters for {cls.__name__}: {detail}",
            path=getattr(exc, "param", ""),
        ) from exc
