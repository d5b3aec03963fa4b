"""SUMO vehicle-type parameters: Flow's ``SumoCarFollowingParams`` and ``SumoLaneChangeParams``.

Both are plain mutable data (Flow code sets ``params.min_gap = 0``) whose values are checked
when a config is loaded (:mod:`flowrun.config.checks`). Flow's ``controller_params`` — the
SUMO ``<vType>`` attributes in SUMO's spelling — is a view of the fields: reading it gives
the current values, writing a key sets the field. :func:`vtype_attributes` is what the
``.rou.xml`` writer puts on each ``<vType>``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

from flowrun.config.compat import flow_keywords
from flowrun.config.modes import lane_change_mode_value, speed_mode_value
from flowrun.suggest import did_you_mean

log = logging.getLogger(__name__)

#: SUMO ``<vType>`` attribute -> ``SumoCarFollowingParams`` field (Flow's ``controller_params``).
CAR_FOLLOWING_ATTRIBUTES: dict[str, str] = {
    "accel": "accel",
    "decel": "decel",
    "sigma": "sigma",
    "tau": "tau",
    "minGap": "min_gap",
    "maxSpeed": "max_speed",
    "speedFactor": "speed_factor",
    "speedDev": "speed_dev",
    "impatience": "impatience",
    "carFollowModel": "car_follow_model",
}
#: SUMO attribute -> ``SumoLaneChangeParams`` field, for both lane-change models.
LC2013_ATTRIBUTES: dict[str, str] = {
    "laneChangeModel": "model",
    "lcStrategic": "lc_strategic",
    "lcCooperative": "lc_cooperative",
    "lcSpeedGain": "lc_speed_gain",
    "lcKeepRight": "lc_keep_right",
}
#: ... and those only the sublane model ``SL2015`` gets (as in Flow).
SL2015_ATTRIBUTES: dict[str, str] = {
    **LC2013_ATTRIBUTES,
    "lcLookaheadLeft": "lc_look_ahead_left",
    "lcSpeedGainRight": "lc_speed_gain_right",
    "lcSublane": "lc_sublane",
    "lcPushy": "lc_pushy",
    "lcPushyGap": "lc_pushy_gap",
    "lcAssertive": "lc_assertive",
    "lcAccelLat": "lc_accel_lat",
}
#: Attributes Flow's last release no longer writes; flowrun writes them when not the default.
EXTRA_LANE_CHANGE_ATTRIBUTES: dict[str, str] = {
    "lcImpatience": "lc_impatience",
    "lcTimeToImpatience": "lc_time_to_impatience",
}
LANE_CHANGE_MODELS = ("LC2013", "SL2015")


class SumoAttributes(dict[str, Any]):
    """Flow's ``controller_params``: a dict of SUMO attributes that writes through to fields.

    A fresh one is made at each read of ``controller_params`` (so it shows the current
    fields); setting a key sets the field (``["minGap"] = 0`` is ``min_gap = 0``).
    """

    def __init__(self, owner: Any, names: dict[str, str], as_text: bool) -> None:
        self._owner = owner
        self._names = names
        self._as_text = as_text
        super().__init__({key: self._shown(getattr(owner, f)) for key, f in names.items()})

    def _shown(self, value: Any) -> Any:
        return str(value) if self._as_text else value

    def __setitem__(self, key: str, value: Any) -> None:
        if key not in self._names:
            raise KeyError(
                f"'{key}' is not a SUMO attribute of {type(self._owner).__name__}"
                f"{did_you_mean(key, self._names)}; it has: {', '.join(self._names)}"
            )
        name = self._names[key]
        current = getattr(self._owner, name)
        if isinstance(value, str) and isinstance(current, int | float):
            value = float(value)  # Flow keeps the lane-change numbers as text
        setattr(self._owner, name, value)
        super().__setitem__(key, self._shown(getattr(self._owner, name)))

    def update(self, *args: Any, **kwargs: Any) -> None:
        """Set several attributes (each one as ``d[key] = value``)."""
        for key, value in dict(*args, **kwargs).items():
            self[key] = value

    def setdefault(self, key: str, default: Any = None) -> Any:
        """The attribute's value (every attribute always has one)."""
        if key not in self:
            self[key] = default
        return self[key]

    def __delitem__(self, key: str) -> None:
        raise TypeError("a vehicle type always has every attribute; set it instead")

    def pop(self, *args: Any) -> Any:
        """Refused: see :meth:`__delitem__`."""
        raise TypeError("a vehicle type always has every attribute; set it instead")

    def popitem(self) -> tuple[str, Any]:
        """Refused: see :meth:`__delitem__`."""
        raise TypeError("a vehicle type always has every attribute; set it instead")

    def clear(self) -> None:
        """Refused: see :meth:`__delitem__`."""
        raise TypeError("a vehicle type always has every attribute; set it instead")


@flow_keywords({camel: snake for camel, snake in CAR_FOLLOWING_ATTRIBUTES.items()
                if camel != snake})  # fmt: skip
@dataclass
class SumoCarFollowingParams:
    """SUMO vehicle-type parameters (Flow's ``SumoCarFollowingParams``).

    Flow's camelCase keywords (``minGap``, ``maxSpeed``, ``speedFactor``, ``speedDev``,
    ``carFollowModel``) are accepted with a ``DeprecationWarning`` and mean the same as the
    field. flowrun's defaults differ from Flow's on purpose in three places:
    ``speed_mode=0`` ("aggressive": SUMO applies a controller's command as is; Flow's
    ``right_of_way`` lets SUMO's safe-speed cap damp IDM braking), ``decel=7.5`` (Flow 4.5)
    and ``speed_dev=0`` (Flow 0.1: homogeneous drivers, as in the published ring results).

    Attributes:
        speed_mode: SUMO ``speedMode``, stored as Flow stores it: an int. A name of
            :data:`~flowrun.config.modes.SPEED_MODES` is turned into its int when given
            (also when set later: ``p.speed_mode = "all_checks"`` stores 31).
        accel: max acceleration, m/s^2 (SUMO's own model; also the cap of flowrun's
            controllers, as in Flow).
        decel: comfortable deceleration, m/s^2.
        sigma: driver imperfection of SUMO's own model (0..1).
        tau: desired time headway of SUMO's own model, s.
        min_gap: standstill gap SUMO keeps, m (SUMO ``minGap``).
        max_speed: vehicle-type maximum speed, m/s (SUMO ``maxSpeed``).
        speed_factor: multiplier of the lane speed limit (SUMO ``speedFactor``).
        speed_dev: std of the speed factor across vehicles (SUMO ``speedDev``).
        impatience: SUMO ``impatience`` (0..1).
        car_follow_model: SUMO's car-following model for SUMO-driven cars
            (``carFollowModel``).
        length: vehicle length, m (flowrun's addition; Flow leaves SUMO's default 5 m).
    """

    speed_mode: int | str = 0
    accel: float = 2.6
    decel: float = 7.5
    sigma: float = 0.5
    tau: float = 1.0
    min_gap: float = 2.5
    max_speed: float = 30.0
    speed_factor: float = 1.0
    speed_dev: float = 0.0
    impatience: float = 0.5
    car_follow_model: str = "IDM"
    length: float = 5.0

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "speed_mode":
            value = speed_mode_value(value)
        super().__setattr__(name, value)

    @property
    def controller_params(self) -> SumoAttributes:
        """Flow's dict of SUMO ``<vType>`` attributes (``{"minGap": 2.5, ...}``), live."""
        return SumoAttributes(self, CAR_FOLLOWING_ATTRIBUTES, as_text=False)


@flow_keywords({"lcStrategic": "lc_strategic", "lcCooperative": "lc_cooperative",
                "lcSpeedGain": "lc_speed_gain", "lcKeepRight": "lc_keep_right",
                "lcLookaheadLeft": "lc_look_ahead_left",
                "lcSpeedGainRight": "lc_speed_gain_right", "lcSublane": "lc_sublane",
                "lcPushy": "lc_pushy", "lcPushyGap": "lc_pushy_gap",
                "lcAssertive": "lc_assertive", "lcImpatience": "lc_impatience",
                "lcTimeToImpatience": "lc_time_to_impatience",
                "lcAccelLat": "lc_accel_lat"})  # fmt: skip
@dataclass
class SumoLaneChangeParams:
    """SUMO lane-change parameters (Flow's ``SumoLaneChangeParams``), Flow's defaults.

    Flow's camelCase keywords (``lcStrategic``, ``lcLookaheadLeft``, ...) are accepted with a
    ``DeprecationWarning``. As in Flow, a ``model`` other than ``LC2013``/``SL2015`` given in
    Python falls back to ``LC2013`` with a logged warning (the YAML refuses it), and only
    ``SL2015`` writes the sublane attributes (``lc_look_ahead_left`` ... ``lc_accel_lat``).

    Attributes:
        lane_change_mode: SUMO ``laneChangeMode``, stored as an int; a name of
            :data:`~flowrun.config.modes.LANE_CHANGE_MODES` is turned into its int.
        model: SUMO lane-change model (``laneChangeModel``): ``LC2013`` or ``SL2015``
            (the sublane model; needs ``SumoParams.lateral_resolution``).
        lc_strategic: eagerness for strategic lane changes (``lcStrategic``).
        lc_cooperative: willingness to cooperate (``lcCooperative``).
        lc_speed_gain: eagerness to change lanes for speed (``lcSpeedGain``).
        lc_keep_right: eagerness to keep right (``lcKeepRight``).
        lc_look_ahead_left: look-ahead factor for left changes (``lcLookaheadLeft``, SL2015).
        lc_speed_gain_right: speed-gain eagerness to the right (``lcSpeedGainRight``, SL2015).
        lc_sublane: eagerness for sublane changes (``lcSublane``, SL2015).
        lc_pushy: willingness to encroach laterally (``lcPushy``, SL2015).
        lc_pushy_gap: minimum lateral gap when pushing, m (``lcPushyGap``, SL2015).
        lc_assertive: willingness to accept smaller gaps (``lcAssertive``, SL2015).
        lc_accel_lat: max lateral acceleration, m/s^2 (``lcAccelLat``, SL2015).
        lc_impatience: impatience growth (``lcImpatience``; older Flow). Written to SUMO
            only when not 0.
        lc_time_to_impatience: s until full impatience (``lcTimeToImpatience``; older Flow).
            Written to SUMO only when finite.
    """

    lane_change_mode: int | str = 512
    model: str = "LC2013"
    lc_strategic: float = 1.0
    lc_cooperative: float = 1.0
    lc_speed_gain: float = 1.0
    lc_keep_right: float = 1.0
    lc_look_ahead_left: float = 2.0
    lc_speed_gain_right: float = 1.0
    lc_sublane: float = 1.0
    lc_pushy: float = 0.0
    lc_pushy_gap: float = 0.6
    lc_assertive: float = 1.0
    lc_accel_lat: float = 1.0
    lc_impatience: float = 0.0
    lc_time_to_impatience: float = math.inf

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "lane_change_mode":
            value = lane_change_mode_value(value)
        elif name == "model" and value not in LANE_CHANGE_MODELS:
            log.warning("unknown lane-change model %r: using LC2013 (as Flow does)", value)
            value = "LC2013"
        super().__setattr__(name, value)

    @property
    def controller_params(self) -> SumoAttributes:
        """Flow's dict of SUMO lane-change attributes (text values, as Flow keeps them), live.

        ``LC2013`` has ``laneChangeModel`` and the four ``lcStrategic`` ... ``lcKeepRight``;
        ``SL2015`` adds the seven sublane attributes.
        """
        names = SL2015_ATTRIBUTES if self.model == "SL2015" else LC2013_ATTRIBUTES
        return SumoAttributes(self, names, as_text=True)


def _text(value: Any) -> str:
    return str(value)


def vtype_attributes(
    car_following: SumoCarFollowingParams, lane_change: SumoLaneChangeParams
) -> dict[str, str]:
    """The SUMO ``<vType>`` attributes of one vehicle group, SUMO's spelling, text values.

    ``length``, then Flow's car-following ``controller_params`` and lane-change
    ``controller_params`` (what Flow writes), then ``lcImpatience``/``lcTimeToImpatience``
    when they are not the defaults. ``id`` and ``color`` are the writer's to add.
    """
    out = {"length": _text(car_following.length)}
    out.update({k: _text(v) for k, v in car_following.controller_params.items()})
    out.update({k: _text(v) for k, v in lane_change.controller_params.items()})
    if lane_change.lc_impatience != 0:
        out["lcImpatience"] = _text(lane_change.lc_impatience)
    if math.isfinite(lane_change.lc_time_to_impatience):
        out["lcTimeToImpatience"] = _text(lane_change.lc_time_to_impatience)
    return out
