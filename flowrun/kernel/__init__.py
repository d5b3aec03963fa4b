"""The kernel: the only layer that talks to SUMO (libsumo, or TraCI for a GUI)."""

from flowrun.kernel.kernel import Kernel

__all__ = ["Kernel"]
