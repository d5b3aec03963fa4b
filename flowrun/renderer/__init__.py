"""Flow compatibility: re-exports. Flow's ``flow.renderer`` path.

``flowrun.renderer.pyglet_renderer.PygletRenderer`` is :class:`flowrun.render.flow_frames.
PygletRenderer` (drawn headless with PIL; no OpenGL window).
"""
