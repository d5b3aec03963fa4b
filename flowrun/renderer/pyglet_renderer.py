"""Flow compatibility: re-exports. Flow's ``flow.renderer.pyglet_renderer`` path.

The renderer lives in :mod:`flowrun.render.flow_frames`.
"""

from flowrun.render.flow_frames import PygletRenderer

__all__ = ["PygletRenderer"]
