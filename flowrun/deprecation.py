"""Flow's deprecation helpers (``flow.utils.flow_warnings``): a warning for a renamed
attribute, and a decorator marking a class or function as moved."""

from __future__ import annotations

import functools
import inspect
import warnings
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")


def deprecated_attribute(obj: object, dep_from: str, dep_to: str) -> None:
    """Warn (``PendingDeprecationWarning``, Flow's message) that ``obj.<dep_from>`` is now
    ``<dep_to>``."""
    warnings.warn(
        f"The attribute {dep_from} in {type(obj).__name__} is deprecated, use {dep_to} instead.",
        PendingDeprecationWarning,
        stacklevel=2,
    )


def deprecated(base: str, new_path: str) -> Callable[[T], T]:
    """Decorator: using the class (instantiating it) or calling the function warns that
    ``<base>.<name>`` is deprecated in favour of ``new_path`` (Flow's message). A class stays
    a class (``isinstance`` and subclassing keep working)."""

    def decorator(obj: T) -> T:
        kind = "class" if inspect.isclass(obj) else "function"
        name = getattr(obj, "__name__", obj)
        message = f"The {kind} {base}.{name} is deprecated, use {new_path} instead."

        def warn() -> None:
            warnings.warn(message, PendingDeprecationWarning, stacklevel=3)

        if inspect.isclass(obj):
            init = obj.__init__

            @functools.wraps(init)
            def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
                warn()
                init(self, *args, **kwargs)

            setattr(obj, "__init__", __init__)  # noqa: B010
            return obj
        func: Any = obj

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            warn()
            return func(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorator
