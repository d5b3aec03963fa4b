"""The ``.rou.xml`` of an episode: vehicle types, routes and inflows."""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from flowrun.config.params import VehicleParams
from flowrun.networks.base import NetworkSpec


def routes_xml(spec: NetworkSpec, vehicles: VehicleParams) -> str:
    """The ``.rou.xml`` text: one vehicle type per group and one route per starting edge."""
    rows = ["<routes>"]
    for g in vehicles.groups:
        cf, lc = g.car_following_params, g.lane_change_params
        color = f" color={quoteattr(g.color)}" if g.color else ""
        rows.append(
            f'    <vType id={quoteattr(g.veh_id)} length="{cf.length}" minGap="{cf.min_gap}" '
            f'maxSpeed="{cf.max_speed}" accel="{cf.accel}" decel="{cf.decel}" '
            f'sigma="{cf.sigma}" tau="{cf.tau}" speedFactor="{cf.speed_factor}" '
            f'speedDev="{cf.speed_dev}" impatience="{cf.impatience}" '
            f"carFollowModel={quoteattr(cf.car_follow_model)} "
            f'laneChangeModel={quoteattr(lc.model)} lcStrategic="{lc.lc_strategic}" '
            f'lcCooperative="{lc.lc_cooperative}" lcSpeedGain="{lc.lc_speed_gain}" '
            f'lcKeepRight="{lc.lc_keep_right}"{color}/>'
        )
    for route_id, edges in spec.routes.items():
        rows.append(
            f"    <route id={quoteattr(route_name(route_id))} edges={quoteattr(' '.join(edges))}/>"
        )
    rows.append("</routes>")
    return "\n".join(rows) + "\n"


def route_name(start_edge: str) -> str:
    """SUMO id of the route that starts on ``start_edge``."""
    return f"route_{start_edge}"
