"""Spaces that answer both ways: Flow's ``env.observation_space`` (a property giving every
agent's space) and PettingZoo's ``env.observation_space(agent)`` (a method).

A Flow user's multi-agent env declares ``observation_space`` and ``action_space`` as
properties; PettingZoo and RLlib call them with an agent. :func:`callable_space` gives a space
(still a ``Box``, ``Discrete``, ... for ``isinstance`` and equality) that returns itself when
called with an agent, and :class:`FlowSpace` is the attribute that replaces such a property.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import gymnasium

S = TypeVar("S", bound=gymnasium.Space[Any])
_CALLABLE: dict[type, type] = {}


def _call(self: Any, agent: Any = None) -> Any:
    """PettingZoo's ``observation_space(agent)``: every agent has this space."""
    return self


def callable_space(space: S) -> S:
    """``space`` made callable with an agent (returning itself); same object, same values.

    The class it gets is a subclass of its own named in this module, so it pickles (Ray sends
    spaces to its workers).
    """
    cls = type(space)
    if cls in _CALLABLE.values():
        return space
    made = _CALLABLE.get(cls)
    if made is None:
        name = f"Callable{cls.__name__}"
        made = type(name, (cls,), {"__call__": _call, "__module__": __name__})
        made.__qualname__ = name
        globals()[name] = made
        _CALLABLE[cls] = made
    space.__class__ = made
    return space


class FlowSpace:
    """The attribute replacing a Flow-style ``observation_space``/``action_space`` property.

    Reading it gives the env's space of every agent (stored at construction under ``stored``,
    computed by the property's getter before that), callable with an agent.
    """

    def __init__(self, getter: Callable[[Any], gymnasium.Space[Any]], stored: str) -> None:
        self.getter = getter
        self.stored = stored
        self.__doc__ = getter.__doc__

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        space = obj.__dict__.get(self.stored)
        return space if space is not None else callable_space(self.getter(obj))
