"""Flow's ``flow.core.kernel``: :class:`~flowrun.core.kernel.kernel.Kernel`, Flow's manual
kernel lifecycle over flowrun's kernel."""

from flowrun.core.kernel.kernel import Kernel

__all__ = ["Kernel"]
