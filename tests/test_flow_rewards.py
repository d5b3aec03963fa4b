"""Flow's reward functions (``flowrun.core.rewards``) and the ring envs' Flow-specific details.

No SUMO: the env is a small fake holding numbers; expected values are worked out by hand from
Flow's formulas in the comments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from flowrun.core import rewards
from flowrun.envs.ring.accel import AccelEnv
from flowrun.envs.ring.wave_attenuation import WaveAttenuationEnv, WaveAttenuationPOEnv
from flowrun.errors import FlowrunError
from flowrun.recording import McapRecorder
from flowrun.recording.synthetic import ring_frames
from flowrun.utils.exceptions import FatalFlowError
from flowrun.visualize.time_space_diagram import get_time_space_data, time_space_diagram


@dataclass
class FakeVehicles:
    speed: dict[str, float]
    edge: dict[str, str]
    rl_ids: list[str] = field(default_factory=list)
    previous: dict[str, float] = field(default_factory=dict)
    headway: dict[str, float] = field(default_factory=dict)
    last_lc: dict[str, float] = field(default_factory=dict)
    x: dict[str, float] = field(default_factory=dict)

    @property
    def num_vehicles(self) -> int:
        return len(self.speed)

    @property
    def previous_speeds(self) -> dict[str, float]:
        return self.previous

    def get_ids(self) -> list[str]:
        return list(self.speed)

    def get_rl_ids(self) -> list[str]:
        return self.rl_ids

    def get_ids_by_edge(self, edges: str | list[str]) -> list[str]:
        wanted = {edges} if isinstance(edges, str) else set(edges)
        return [v for v, e in self.edge.items() if e in wanted]

    def get_speed(self, veh_id: str | list[str]) -> Any:
        return self.speed[veh_id] if isinstance(veh_id, str) else [self.speed[v] for v in veh_id]

    def get_previous_speed(self, veh_id: str) -> float:
        return self.previous[veh_id]

    def get_headway(self, veh_id: str) -> float:
        return self.headway[veh_id]

    def get_last_lc(self, veh_id: str) -> float:
        return self.last_lc.get(veh_id, -math.inf)

    def get_x_by_id(self, veh_id: str) -> float:
        return self.x[veh_id]


def fake_env(speeds: list[float], **kw: Any) -> Any:
    ids = [f"car_{i}" for i in range(len(speeds))]
    edges = {v: ("a" if i < 2 else "b") for i, v in enumerate(ids)}
    vehicles = FakeVehicles(dict(zip(ids, speeds, strict=True)), edges, **kw)
    limits = {"a": 20.0, "b": 30.0}
    network = SimpleNamespace(
        speed_limit=limits.__getitem__, get_edge_list=lambda: list(limits), length=lambda: 100.0
    )
    return SimpleNamespace(
        k=SimpleNamespace(vehicle=vehicles, network=network),
        env_params=SimpleNamespace(additional_params={"target_velocity": 10}, evaluate=False),
        sim_step=0.1,
        timer=5,
    )


def test_desired_velocity_over_all_cars_and_over_an_edge_list() -> None:
    env = fake_env([10.0, 0.0, 0.0, 0.0])
    # |t| = 10*sqrt(4) = 20, |v - t| = sqrt(3*100) -> (20 - 17.3205)/20
    assert rewards.desired_velocity(env) == pytest.approx((20 - math.sqrt(300)) / 20)
    # edge "a" holds car_0 (10) and car_1 (0): 1 - 10/(10*sqrt(2))
    assert rewards.desired_velocity(env, edge_list=["a"]) == pytest.approx(1 - 1 / math.sqrt(2))
    assert rewards.desired_velocity(env, fail=True) == 0.0
    assert rewards.desired_velocity(fake_env([10.0, -101.0])) == 0.0


def test_average_and_total_velocity() -> None:
    env = fake_env([10.0, 0.0, 0.0, 0.0])
    assert rewards.average_velocity(env) == pytest.approx(2.5)
    assert rewards.total_velocity(env) == pytest.approx(10.0)
    assert rewards.average_velocity(env, fail=True) == 0.0
    assert rewards.total_velocity(env, fail=True) == 0.0
    assert rewards.average_velocity(fake_env([])) == 0.0


def test_delay_rewards() -> None:
    env = fake_env([10.0, 0.0, 0.0, 0.0])
    # v_top = 30: delay = 0.1*(20/30 + 3) = 0.366667; max = 0.1*4 = 0.4
    assert rewards.min_delay(env) == pytest.approx((0.4 - 0.1 * (2 / 3 + 3)) / 0.4)
    assert rewards.min_delay_unscaled(env) == pytest.approx(0.1 * (2 / 3 + 3) / 4)
    assert rewards.min_delay(fake_env([])) == 0.0
    # against each edge's limit: a (20): 10/20 + 1, b (30): 1 + 1 -> 0.1*3.5 / 2 ids
    assert rewards.avg_delay_specified_vehicles(env, ["car_0", "car_1"]) == pytest.approx(0.175)
    assert rewards.avg_delay_specified_vehicles(env, []) == 0.0


def test_standstill_penalties_and_boolean_actions() -> None:
    env = fake_env([10.0, 0.2, 0.0, 0.0])
    assert rewards.penalize_standstill(env, gain=2) == -4
    assert rewards.penalize_near_standstill(env) == -3  # 0.2, 0, 0 below 0.3 m/s
    assert rewards.penalize_near_standstill(env, thresh=0.1, gain=3) == -6
    assert rewards.boolean_action_penalty([True, False, True], gain=0.5) == 1.0
    assert rewards.boolean_action_penalty([False, False]) == 0.0


def test_rl_progress_lane_changes_and_headway_variance() -> None:
    env = fake_env(
        [10.0, 4.0], rl_ids=["car_0", "car_1"], last_lc={"car_0": 5}, headway={"car_0": 2.0,
                                                                             "car_1": 4.0}
    )  # fmt: skip
    assert rewards.rl_forward_progress(env) == pytest.approx(1.4)
    assert rewards.punish_rl_lane_changes(env, penalty=2) == -2  # car_0 changed at timer 5
    assert rewards.penalize_headway_variance(env.k.vehicle, ["car_0", "car_1"]) == -1.0


def test_energy_consumption_from_speed_and_previous_speed() -> None:
    # car_0 from 0 to 1 m/s in 0.1 s: 1200*1*10 + 1200*9.81*0.005*1 + 0.5*1.225*2.6*0.3*1
    expected = -0.001 * (12000 + 58.86 + 0.47775)
    env = fake_env([1.0, 0.0], previous={"car_0": 0.0, "car_1": 0.0})
    assert rewards.energy_consumption(env) == pytest.approx(expected)
    assert rewards.vehicle_energy_consumption(env, "car_0") == pytest.approx(expected)
    assert rewards.energy_consumption(fake_env([0.0], previous={"car_0": 0.0}), gain=1) == 0.0
    # a car without a previous speed (just entered) is skipped
    assert rewards.energy_consumption(fake_env([1.0], previous={})) == 0.0
    # 1 m/s over 12059.33775 W, in miles per megajoule
    mpj = 1 / 12059.33775 / 1609 * 1e6 * 0.001
    assert rewards.miles_per_megajoule(env, "car_0") == pytest.approx(mpj)


@pytest.mark.parametrize("cls", [WaveAttenuationEnv, WaveAttenuationPOEnv])
def test_wave_attenuation_reward_is_zero_without_actions(cls: Any) -> None:
    env = fake_env([5.0, 5.0])
    env.k.vehicle.speed = np.array([5.0, 5.0])
    # with an action: 4*5/20 - 4*0.5 = -1; without (warm-up): 0, as in Flow
    assert cls.compute_reward(env, np.array([0.5]), fail=False) == pytest.approx(-1.0)
    assert cls.compute_reward(env, None, fail=False) == 0.0
    env.env_params.evaluate = True
    assert cls.compute_reward(env, None, fail=False) == 0.0


def test_accel_env_sorted_ids_and_absolute_position_are_flows_properties() -> None:
    env = fake_env([1.0, 2.0, 3.0], x={"car_0": 250.0, "car_1": 10.0, "car_2": 99.0})
    env._get_abs_position = lambda v: AccelEnv._get_abs_position(env, v)
    absolute_position, sorted_ids = (
        vars(AccelEnv)[n].fget for n in ("absolute_position", "sorted_ids")
    )
    assert absolute_position(env) == {"car_0": 50.0, "car_1": 10.0, "car_2": 99.0}
    assert sorted_ids(env) == ["car_0", "car_1", "car_2"]  # not sorting
    env.env_params.additional_params["sort_vehicles"] = True
    assert sorted_ids(env) == ["car_1", "car_0", "car_2"]


def test_fatal_flow_error_is_a_flowrun_error() -> None:
    with pytest.raises(FlowrunError, match="cannot continue"):
        raise FatalFlowError("cannot continue")


def test_time_space_diagram_from_an_mcap_log(tmp_path: Path) -> None:
    log = tmp_path / "ring.mcap"
    with McapRecorder(log, metadata={"config_name": "ring", "seed": "0"}) as rec:
        for frame, stats in ring_frames(4, 20):
            rec.write(frame, stats)
    times, positions, speeds, ids = get_time_space_data(log)
    assert times.size == positions.size == speeds.size == len(ids) == 4 * 20
    out = time_space_diagram(log)
    assert out == tmp_path / "ring_tsd.png" and out.stat().st_size > 0


def test_desired_velocity_at_the_target_is_exactly_one_and_from_rest_exactly_zero() -> None:
    # Flow takes the norm of the target vector, so these are exact (not 1 - 1e-16)
    assert rewards.desired_velocity(fake_env([10.0] * 22)) == pytest.approx(1.0, abs=1e-6)
    assert rewards.desired_velocity(fake_env([0.0] * 22)) == 0.0


def test_headway_shaping_rewards_for_rl_cars() -> None:
    class WithFollowers(FakeVehicles):
        def get_follower(self, veh_id: str) -> str | None:
            return {"car_0": "car_1", "car_2": None}.get(veh_id)

    env = fake_env([5.0, 5.0, 5.0])
    env.k.vehicle = WithFollowers(
        env.k.vehicle.speed, env.k.vehicle.edge, rl_ids=["car_0", "car_2"],
        headway={"car_0": 2.0, "car_1": 12.0, "car_2": 10.0},
    )  # fmt: skip
    # threshold 5: only car_0 (2 m) is below: ((5 - 2) / 5) ** 2 * 3 = 1.08, as a penalty
    assert rewards.punish_small_rl_headways(env, 5, penalty_gain=3, penalty_exponent=2) == (
        pytest.approx(-1.08)
    )
    # car_0's follower car_1 keeps 12 m; car_2 has none: 0.1 * 12
    assert rewards.reward_rl_opening_headways(env) == pytest.approx(1.2)


def test_queue_penalty_counts_the_cars_of_one_lane() -> None:
    class Lanes(FakeVehicles):
        def get_lane(self, veh_id: str) -> int:
            return {"car_2": 0, "car_3": 1}.get(veh_id, 0)

    env = fake_env([1.0, 1.0, 1.0, 1.0])
    env.k.vehicle = Lanes(env.k.vehicle.speed, env.k.vehicle.edge)
    # edge "b" holds car_2 (lane 0) and car_3 (lane 1)
    assert rewards.punish_queues_in_lane(env, "b", 0, penalty_gain=2, penalty_exponent=2) == -2
