"""``InitialConfig`` on the ring as Flow has it: edges_distribution, negative bunching,
``custom`` spacing through the network's own ``gen_custom_start_pos``, unknown spacings."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from flowrun.config.params import InitialConfig, NetParams, VehicleParams
from flowrun.errors import ConfigError
from flowrun.networks.ring import RingNetwork


def ring(initial: InitialConfig, cls: type[RingNetwork] = RingNetwork, n: int = 8) -> RingNetwork:
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=n)
    return cls("r", vehicles, NetParams(additional_params={"length": 230}), initial)


def place(net: RingNetwork) -> Any:
    return net.start_positions(np.random.default_rng(0))


def test_edges_distribution_puts_every_car_on_the_named_edges() -> None:
    start = place(ring(InitialConfig(edges_distribution=["bottom", "right"])))
    assert set(start.edges) <= {"bottom", "right"}
    assert len(start.edges) == 8


def test_negative_bunching_places_as_zero_bunching() -> None:
    a = place(ring(InitialConfig(bunching=-30)))
    b = place(ring(InitialConfig(bunching=0)))
    assert a == b
    assert place(ring(InitialConfig(bunching=20))) != b


def test_custom_spacing_asks_the_networks_own_generator() -> None:
    class Custom(RingNetwork):
        @staticmethod
        def gen_custom_start_pos(cls: Any, net_params: Any, initial_config: Any, n: int) -> Any:
            return [("top", 1.0 + 10 * i) for i in range(n)], [0] * n

    start = place(ring(InitialConfig(spacing="custom"), Custom, n=3))
    assert start.edges == ["top"] * 3
    assert start.lane_pos == [1.0, 11.0, 21.0]


def test_custom_spacing_without_a_generator_and_unknown_spacings_are_refused() -> None:
    with pytest.raises(ConfigError, match="defines none"):
        place(ring(InitialConfig(spacing="custom")))
    initial = replace(InitialConfig(), spacing="unifrom")
    with pytest.raises(ConfigError, match="did you mean 'uniform'"):
        place(ring(initial))
