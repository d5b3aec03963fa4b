"""The kernel: the only layer that talks to SUMO (libsumo, or TraCI for a GUI)."""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from flowrun.kernel.kernel import Kernel


def __getattr__(name: str) -> Any:
    """``Kernel``, imported on first use (importing a kernel module such as
    :mod:`flowrun.kernel.population` does not import SUMO's bindings)."""
    if name != "Kernel":
        raise AttributeError(f"module 'flowrun.kernel' has no attribute '{name}'")
    from flowrun.kernel.kernel import Kernel

    return Kernel


__all__ = ["Kernel"]
