"""A user's own road as a network type: a SUMO ``.net.xml`` (``NetParams(template=...)``) or an
OpenStreetMap file converted by netconvert (``NetParams(osm_path=...)``), read by
:mod:`flowrun.networks.template_read`.

Routes come from the ``routes`` parameter (YAML ``network.routes``) or a subclass's
Flow-style ``specify_routes(net_params)``: start edge -> list of edges, or start edge -> list
of ``(edges, probability)`` choices. Without routes, a car's route is its start edge.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from flowrun.errors import ConfigError
from flowrun.networks.base import Network
from flowrun.networks.spec import NetworkSpec
from flowrun.networks.template_read import template_spec

ADDITIONAL_NET_PARAMS: dict[str, Any] = {
    # start edge -> [edges] or [[edges, probability], ...]; None: each car drives its edge
    "routes": None,
}


class TemplateNetwork(Network):
    """A network read from a ``.net.xml`` (Flow's ``NetParams(template=...)``) or an OSM file.

    ``net_params.template``: the ``.net.xml`` path, or Flow's dict ``{net, rou, vtype}``;
    ``net_params.osm_path``: an OpenStreetMap file. ``additional_params``: ``routes``.
    Subclasses may define Flow's ``specify_routes(net_params)`` instead.
    """

    ADDITIONAL_NET_PARAMS: ClassVar[dict[str, Any]] = ADDITIONAL_NET_PARAMS
    network_type: ClassVar[str] = "template"
    LIST_NOTE: ClassVar[str] = "with template: file.net.xml or osm_path: file.osm"

    @classmethod
    def resolve_params(cls, given: dict[str, Any]) -> dict[str, Any]:
        """Merge with defaults; ``routes`` must be a mapping (checked against the file later)."""
        params = super().resolve_params(given)
        if params["routes"] is not None and not isinstance(params["routes"], Mapping):
            raise ConfigError(
                "expected a mapping start edge -> [edges] or [[edges, probability], ...], "
                f"got {params['routes']!r}",
                path="routes",
            )
        return params

    def build_spec(self) -> NetworkSpec:
        """Read the network file's edges and the routes."""
        return template_spec(self.net_params, self.specify_routes(self.net_params))

    def specify_routes(self, net_params: Any) -> Mapping[str, Any]:
        """Flow's hook: start edge -> route (or route choices); default the ``routes`` param."""
        return self.params.get("routes") or {}

