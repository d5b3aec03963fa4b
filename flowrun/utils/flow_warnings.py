"""Flow's ``flow.utils.flow_warnings``: a deprecation notice for a renamed attribute."""

from __future__ import annotations

import warnings


def deprecation_warning(obj: object, dep_from: str, dep_to: str) -> None:
    """Warn that an attribute of ``obj`` was renamed (Flow's message, as a ``UserWarning``).

    Args:
        obj: the object whose attribute was used under its old name.
        dep_from: the old attribute name.
        dep_to: the name to use instead.
    """
    warnings.warn(
        f"The attribute {dep_from} in {type(obj).__name__} is deprecated, use {dep_to} instead.",
        UserWarning,
        stacklevel=2,
    )
