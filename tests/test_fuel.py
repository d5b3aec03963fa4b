"""Fuel: the kernel's ``get_fuel_consumption`` (SUMO's mg/s as US gallons/s) and Flow's
``miles_per_gallon`` over it, on a real SUMO ring where the cars speed up from rest."""

from __future__ import annotations

import math

import pytest

from flowrun.config.params import (
    ControllerSpec,
    EnvParams,
    InitialConfig,
    NetParams,
    SumoParams,
    VehicleParams,
)
from flowrun.core import rewards
from flowrun.kernel.vehicle_api import MG_PER_GALLON
from flowrun.networks.ring import RingNetwork
from tests.test_open_kernel import Drive


def test_miles_per_gallon_from_sumos_fuel_on_a_moving_ring() -> None:
    vehicles = VehicleParams()
    vehicles.add("human", acceleration_controller=ControllerSpec("IDM", {}), num_vehicles=6)
    net = RingNetwork("ring", vehicles, NetParams(additional_params={"length": 230, "lanes": 1,
                      "speed_limit": 30, "resolution": 40}), InitialConfig())  # fmt: skip
    env = Drive(EnvParams(horizon=100), SumoParams(sim_step=0.1, seed=0), net)
    env.reset(seed=0)
    try:
        for _ in range(50):
            env.step(None)
        k = env.k.vehicle
        ids = k.get_ids()
        speeds = k.get_speed(ids)
        gallons = k.get_fuel_consumption(ids)
        assert min(speeds) > 0.5  # the cars are moving
        # the getter is SUMO's own mg/s divided by the mg in a gallon (745 g/l gasoline)
        mg_per_s = [env.k.vehicle.api.vehicle.getFuelConsumption(v) for v in ids]
        assert gallons == pytest.approx([m / MG_PER_GALLON for m in mg_per_s])
        assert round(MG_PER_GALLON) == 2_820_132  # 745 g/l * 1000 mg/g * 3.785411784 l
        assert all(g > 0 for g in gallons)
        # a small car driving a few m/s burns between 1e-6 and 1e-3 gallons per second
        assert all(1e-6 < g < 1e-3 for g in gallons)
        mpg = rewards.miles_per_gallon(env, gain=1.0)
        expected = sum(v / g for v, g in zip(speeds, gallons, strict=True)) / len(ids) / 1609.0
        assert math.isfinite(mpg) and mpg > 0
        assert mpg == pytest.approx(expected)
        assert rewards.miles_per_gallon(env) == pytest.approx(expected * 0.001)  # Flow's gain
        one = ids[0]
        assert rewards.miles_per_gallon(env, one, gain=1.0) == pytest.approx(
            speeds[0] / gallons[0] / 1609.0
        )
        assert k.get_fuel_consumption("nobody") == -1001
        print(f"mpg {mpg:.2f}, speeds {min(speeds):.2f}-{max(speeds):.2f} m/s, "
              f"fuel {min(mg_per_s):.0f}-{max(mg_per_s):.0f} mg/s")  # fmt: skip
    finally:
        env.close()
