"""Flow's bottleneck on real SUMO: the network netconvert builds, positions through the
zipper merges, the capacity drop, and the bottleneck environments."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from flowrun.config.params import InitialConfig, NetParams, VehicleParams
from flowrun.config.vtype import vtype_attributes
from flowrun.envs import (
    BottleneckAccelEnv,
    BottleneckDesiredVelocityEnv,
    BottleneckEnv,
    DesiredVelocityEnv,
)
from flowrun.envs.factory import make_env
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config, override_config
from flowrun.networks import BottleneckNetwork
from flowrun.networks.bottleneck import bottleneck_edge_starts, zipper_link
from flowrun.networks.build import build_network
from flowrun.networks.registry import network_class
from flowrun.scenarios import BottleneckScenario

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


@contextmanager
def env_of(name: str, *overrides: str) -> Iterator[Any]:
    env = make_env(load_config(CONFIGS / f"{name}.yaml", list(overrides)))
    try:
        yield env
    finally:
        env.close()


def built(tmp_path: Path, scaling: int) -> tuple[BottleneckNetwork, ET.Element]:
    net = BottleneckNetwork(
        "b", VehicleParams(), NetParams(additional_params={"scaling": scaling}), InitialConfig()
    )
    return net, ET.parse(build_network(net.spec, tmp_path, "bottleneck")).getroot()


@pytest.mark.parametrize("scaling", [1, 2])
def test_lanes_drop_4s_2s_1s_through_zipper_merges(tmp_path: Path, scaling: int) -> None:
    net, root = built(tmp_path, scaling)
    edges = {e.get("id"): e.findall("lane") for e in root.iter("edge") if not e.get("function")}
    assert {k: len(v) for k, v in edges.items()} == {
        "1": 4 * scaling, "2": 4 * scaling, "3": 4 * scaling, "4": 2 * scaling, "5": scaling
    }  # fmt: skip
    lengths = {k: float(v[0].get("length", "nan")) for k, v in edges.items()}
    assert lengths == pytest.approx({"1": 100, "2": 310, "3": 140, "4": 280, "5": 155})
    # lanes centred on the road's line (Flow's spreadType "center"): each merge is symmetric
    lane_y = {k: [float(lane.get("shape", "").split()[0].split(",")[1]) for lane in v]
              for k, v in edges.items()}  # fmt: skip
    assert {k: sum(y) for k, y in lane_y.items()} == pytest.approx(dict.fromkeys(edges, 0.0))
    assert max(lane_y["3"]) == pytest.approx(1.6 * 4 * scaling - 1.6)  # 3.2 m lanes
    kinds = {j.get("id"): j.get("type") for j in root.iter("junction")}
    assert kinds["4"] == kinds["5"] == "zipper"
    links = {(c.get("from"), c.get("fromLane"), c.get("to"), c.get("toLane"))
             for c in root.iter("connection") if c.get("from") in ("3", "4")}  # fmt: skip
    # Flow's toLane = floor(i / 2): two lanes merge into one, alternately
    assert links == {("3", str(i), "4", str(i // 2)) for i in range(4 * scaling)} | {
        ("4", str(i), "5", str(i // 2)) for i in range(2 * scaling)
    }
    assert net.spec.routes["1"] == ("1", "2", "3", "4", "5")
    assert net.get_bottleneck_lanes(3) == [1, 0]
    # the edge starts add the links SUMO built through the zippers, so positions run on
    internal = {e.get("id"): float(e.find("lane").get("length", "nan"))  # type: ignore[union-attr]
                for e in root.iter("edge") if e.get("function") == "internal"}  # fmt: skip
    assert internal[":4_0"] == pytest.approx(zipper_link(4 * scaling), abs=1e-3)
    assert internal[":5_0"] == pytest.approx(zipper_link(2 * scaling), abs=1e-3)
    starts = net.spec.edge_starts
    assert starts["4"] == pytest.approx(starts["3"] + 140 + internal[":4_0"], abs=1e-3)


def test_flow_names_and_bad_parameters() -> None:
    assert network_class("BottleneckScenario") is BottleneckNetwork is BottleneckScenario
    assert DesiredVelocityEnv is BottleneckDesiredVelocityEnv
    from flowrun.envs.bottleneck import BottleneckAccelEnv as FlowPath  # Flow's module paths
    from flowrun.envs.bottleneck_env import DesiredVelocityEnv as OldPath

    assert (FlowPath, OldPath) == (BottleneckAccelEnv, BottleneckDesiredVelocityEnv)
    with pytest.raises(ConfigError, match="integer >= 1"):
        BottleneckNetwork.resolve_params({"scaling": 1.5})
    with pytest.raises(ConfigError, match="unknown parameter"):
        BottleneckNetwork.resolve_params({"scalling": 2})
    assert bottleneck_edge_starts((0.1, 0.1, 40.0, 40.0))["5"] == pytest.approx(
        100 + 310 + 140 + 280 + 80.2
    )


#: Flow's SumoCarFollowingParams() of its last version (flow/core/params.py), which none of
#: Flow's bottleneck set-ups changes beyond the speed mode (flowrun's own defaults differ)
FLOW_DEFAULT_VTYPE = {"accel": 2.6, "decel": 4.5, "sigma": 0.5, "tau": 1.0, "minGap": 2.5,
                      "maxSpeed": 30.0, "speedFactor": 1.0, "speedDev": 0.1,
                      "impatience": 0.5}  # fmt: skip


@pytest.mark.parametrize("name", ["bottleneck", "bottleneck_desired_velocity",
                                  "benchmarks/bottleneck0", "benchmarks/bottleneck1",
                                  "benchmarks/bottleneck2"])  # fmt: skip
def test_bottleneck_cars_get_flows_default_vehicle_type(name: str) -> None:
    groups = load_config(CONFIGS / f"{name}.yaml").vehicles.groups
    assert [g.veh_id for g in groups] in (["human"], ["human", "rl"])
    for g in groups:
        attrs = vtype_attributes(g.car_following_params, g.lane_change_params)
        assert {k: float(attrs[k]) for k in FLOW_DEFAULT_VTYPE} == FLOW_DEFAULT_VTYPE, g.veh_id
        assert (attrs["carFollowModel"], attrs["laneChangeModel"]) == ("IDM", "LC2013")


def outflow(inflow: float, seconds: float = 400.0, window: float = 200.0) -> float:
    """Outflow (veh/h) over the last ``window`` s of an all-human run of ``seconds``."""
    cfg = load_config(CONFIGS / "bottleneck.yaml", [f"network.inflows.0.vehs_per_hour={inflow}"])
    steps = round(seconds / cfg.sim.sim_step)
    env = make_env(override_config(cfg, [f"env.horizon={steps}"]))
    try:
        env.reset(seed=0)
        arrived = 0
        for step in range(steps):
            env.step(None)
            if step >= steps - round(window / cfg.sim.sim_step):
                arrived += len(env.k.vehicle.get_arrived_ids())
    finally:
        env.close()
    return arrived * 3600.0 / window


def test_outflow_rises_with_inflow_then_drops_past_capacity() -> None:
    low, near, over = outflow(1000), outflow(1800), outflow(3000)
    assert low == pytest.approx(1000, rel=0.05)  # below capacity all cars pass
    assert near == pytest.approx(1800, rel=0.05)
    assert over < near - 200  # the merges break down: less passes than at 1,800 veh/h
    assert outflow(3000) == over  # same seed, same run


def test_positions_grow_along_the_road_through_the_zippers() -> None:
    with env_of("bottleneck", "env.horizon=300", "network.inflows.0.vehs_per_hour=600") as env:
        env.reset(seed=0)
        vk = env.k.vehicle
        track: dict[str, list[tuple[float, float, str]]] = {}
        for _ in range(300):
            env.step(None)
            for vid in vk.get_ids():
                track.setdefault(vid, []).append(
                    (vk.get_x_by_id(vid), vk.get_distance(vid), vk.get_edge(vid))
                )
        full = [t for t in track.values() if {e for _, _, e in t} >= {"3", ":4_0", "4", "5"}]
        assert full, "no car drove through both merges"
        for t in full:
            x, odo = np.array([p[0] for p in t]), np.array([p[1] for p in t])
            # the position moves as far as the car drives, across edges and junctions
            assert np.diff(x) == pytest.approx(np.diff(odo), abs=0.05)


def test_humans_change_lanes_only_under_a_mode_that_lets_them() -> None:
    counts = {}
    for mode in ("sumo_default", "no_lc_safe"):
        with env_of("bottleneck", "env.horizon=300",
                    f"vehicles.0.lane_change.lane_change_mode={mode}") as env:  # fmt: skip
            env.reset(seed=0)
            vk = env.k.vehicle
            vk.lane_change_log()
            seen, before = 0, {v: (vk.get_edge(v), vk.get_lane(v)) for v in vk.get_ids()}
            for _ in range(300):
                env.step(None)
                now = {v: (vk.get_edge(v), vk.get_lane(v)) for v in vk.get_ids()}
                changed = {v for v, place in now.items()
                           if v in before and before[v][0] == place[0] != ""
                           and before[v][1] != place[1]}  # fmt: skip
                assert set(vk.get_lane_changes()) == changed
                seen += len(changed)
                before = now
            assert vk.num_lane_changes == seen
            counts[mode] = seen
    assert counts["sumo_default"] > 20
    assert counts["no_lc_safe"] == 0


def test_bottleneck_env_rewards_the_outflow() -> None:
    with env_of("bottleneck", "env.horizon=400", "network.inflows.0.vehs_per_hour=1800") as env:
        assert isinstance(env, BottleneckEnv)
        env.reset(seed=0)
        rewards = [env.step(None)[1] for _ in range(400)]
        # reward = outflow over the last 5 s / 2000: once cars arrive, about 1800 / 2000
        assert np.mean(rewards[200:]) == pytest.approx(0.9, abs=0.1)
        assert np.mean(rewards[:50]) == 0.0  # nobody has reached the end yet


def test_toll_booth_needs_a_traffic_light_on_node_2() -> None:
    with (
        pytest.raises(ConfigError, match="traffic light on node '2'"),
        env_of("bottleneck", "env.additional_params.disable_tb=false"),
    ):
        pass


@pytest.mark.parametrize(("key", "node", "edge", "past"), [
    ("disable_ramp_metering", "3", "2", "3"),  # ALINEA: cars held 80 m before node 3
    ("disable_tb", "2", "1", "2"),  # toll booth: cars held 10 m into edge 1
])  # fmt: skip
def test_flows_ramp_meter_and_toll_booth_switch_their_lights(
    key: str, node: str, edge: str, past: str
) -> None:
    with env_of("bottleneck", f"env.additional_params.{key}=false", "env.horizon=400",
                f"traffic_lights={{lights: [{{node_id: '{node}'}}]}}") as env:  # fmt: skip
        env.reset(seed=0)
        vk, tl = env.k.vehicle, env.k.traffic_light
        states, held_ok, qs = set(), 0, []
        before: dict[str, str] = {}
        for _ in range(400):
            _, _, terminated, _, _ = env.step(None)
            assert not terminated
            states.add(tl.get_state(node))
            now = {vid: vk.get_edge(vid) for vid in vk.get_ids()}
            for vid in vk.get_ids():
                mode = vk.get_lane_change_mode(vid)
                if now[vid] == before.get(vid) == past:  # past the light: its own mode again
                    assert mode == 1621
                if vid in (env.ramp_meter or env.toll_booth).lanes.held:
                    # held from `edge` until the step after it reached `past`
                    assert mode == 512 and (now[vid] == edge or before.get(vid) != past)
                    held_ok += 1
            before = now
            if env.ramp_meter is not None:
                qs.append(env.ramp_meter.q)
        assert held_ok > 100
        assert "GGGG" in states and any("r" in s for s in states)
        if qs:  # ALINEA moved the metered flow within Flow's bounds
            assert 275.0 == min(qs) < max(qs) <= 1100.0


def test_desired_velocity_env_is_flows_bottleneck0() -> None:
    with env_of("bottleneck_desired_velocity", "env.horizon=120") as env:
        assert env.observation_space.shape == (141,)
        assert env.action_space.shape == (20,)
        check_env(env, skip_render_check=True)
        obs, _ = env.reset(seed=3)
        vk = env.k.vehicle
        slow = np.full(20, env.action_space.low[0])  # every cap down by max_decel * dt
        caps: dict[str, float] = {}
        for _ in range(120):
            obs = env.step(slow)[0]
            for rl in vk.get_rl_ids():
                edge = vk.get_edge(rl)
                assert vk.get_max_speed(rl) == pytest.approx(vk.api.vehicle.getMaxSpeed(rl))
                if edge in ("2", "3", "4"):
                    caps[rl] = vk.get_max_speed(rl)
        assert obs.shape == (141,) and obs.min() >= 0.0 and obs.max() <= 1.0
        assert caps and min(caps.values()) < 20.0  # the agent's cuts took effect
        # humans per cell / 20 sum to the humans on the observed edges / 20
        humans = sum(1 for v in vk.get_human_ids() if vk.get_edge(v) in ("1", "2", "3", "4", "5"))
        assert obs[:35].sum() * 20 == pytest.approx(humans)


def test_accel_env_brings_its_av_back_after_it_leaves() -> None:
    with env_of("bottleneck_desired_velocity", "env.class=BottleneckAccelEnv",
                "env.additional_params.add_rl_if_exit=true", "env.warmup_steps=0",
                "env.horizon=400") as env:  # fmt: skip
        assert isinstance(env, BottleneckAccelEnv)
        assert env.rl_id_list == ["rl_0"]
        assert env.observation_space.shape == (4 + 16 + 2 * 5 + 2,)  # + Flow's fake_edge
        check_env(env, skip_render_check=True)
        env.reset(seed=0)
        vk = env.k.vehicle
        path = []
        for _ in range(400):
            obs, reward, _, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
            path.append(vk.get_edge("rl_0") if "rl_0" in vk.table else None)
        left = path.index(None)  # it drove off the end of edge 5 ...
        assert path[left - 1] == "5"
        back = [e for e in path[left:] if e is not None]
        assert back and back[0] == "1"  # ... and entered again at the start
        assert obs.min() >= 0.0 and obs.max() <= 1.0
        rl_speed = sum(vk.get_speed(v) for v in vk.get_rl_ids())
        assert info["reward_terms"]["forward_progress"] == pytest.approx(0.1 * rl_speed)
        assert reward == pytest.approx(sum(info["reward_terms"].values()))


def test_desired_velocity_env_scales_with_the_network_and_redraws_the_inflow() -> None:
    with env_of("bottleneck_desired_velocity", "network.scaling=2", "env.warmup_steps=0",
                "env.additional_params.reset_inflow=true",
                "env.additional_params.inflow_range=[1000, 2000]") as env:  # fmt: skip
        # Flow's bottleneck2: 281 observations, 40 actions
        assert env.observation_space.shape == (281,)
        assert env.action_space.shape == (40,)
        totals = []
        for seed in (0, 1, 0):
            env.reset(seed=seed)
            flows = env.network.net_params.inflows.get()
            rates = [f.vehs_per_hour for f in flows]
            assert rates[1] / sum(rates) == pytest.approx(0.1)  # the AV share is kept
            totals.append(sum(rates))
            env.step(np.zeros(40, dtype=np.float32))
        assert all(2000 <= t <= 4000 for t in totals)  # the range times the scaling
        assert totals[0] == totals[2] != totals[1]  # drawn from the env's seeded generator


def test_symmetric_control_has_one_action_per_segment() -> None:
    with env_of("bottleneck_desired_velocity", "env.additional_params.symmetric=true",
                "env.warmup_steps=0", "env.horizon=60") as env:  # fmt: skip
        assert env.action_space.shape == (6,)  # 2 segments on each of edges 2, 3, 4
        assert env.action_index == {"2": 0, "3": 2, "4": 4}
        env.reset(seed=0)
        vk = env.k.vehicle
        cut = np.zeros(6, dtype=np.float32)
        cut[2:4] = env.action_space.low[0]  # slow down only on edge 3
        checked = {"free": 0, "cut": 0}
        before: dict[str, str] = {}
        for _ in range(60):
            env.step(cut)
            now = {rl: vk.get_edge(rl) for rl in vk.get_rl_ids()}
            for rl, edge in now.items():
                if edge in ("1", "2") and rl in before:  # not cut there: the speed limit
                    assert vk.get_max_speed(rl) == pytest.approx(23.0)
                    checked["free"] += 1
                elif edge == before.get(rl) == "3":  # cut at least twice by now
                    assert vk.get_max_speed(rl) < 23.0 - 1.0
                    checked["cut"] += 1
            before = now
        assert checked["free"] > 0 and checked["cut"] > 0
