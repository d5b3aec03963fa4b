"""Pictures of the traffic on its real road: one renderer for ``--render``, ``rgb_array``, the
HTML player and the Foxglove scene, all reading the network's own lane shapes."""

from flowrun.render.animation import Animation, Snapshot, draw_run, write_animation
from flowrun.render.colours import speed_colours, speed_top
from flowrun.render.picture import FrameLike, Painter, View
from flowrun.render.road import Lane, Road, SignalHead, ring_road, road_from_net_xml

__all__ = [
    "Animation",
    "FrameLike",
    "Lane",
    "Painter",
    "Road",
    "SignalHead",
    "Snapshot",
    "View",
    "draw_run",
    "ring_road",
    "road_from_net_xml",
    "speed_colours",
    "speed_top",
    "write_animation",
]
