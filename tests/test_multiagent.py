"""Multi-agent envs without SUMO: possible agents, reward formulas, registry, optional import."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import gymnasium
import pytest
import typer
from typer.testing import CliRunner

from flowrun.cli.commands_config import register
from flowrun.config.inflows import InFlow, InFlows
from flowrun.config.params import ControllerSpec, VehicleParams
from flowrun.envs.registry import MULTIAGENT_ENVS, env_names, register_envs, resolve_env_class
from flowrun.errors import ConfigError
from flowrun.multiagent.agents import max_departures, possible_agent_ids

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def vehicles(rl: int = 1, human: int = 2) -> VehicleParams:
    v = VehicleParams()
    v.add(veh_id="human", acceleration_controller=ControllerSpec("IDM"), num_vehicles=human)
    v.add(veh_id="rl", acceleration_controller=ControllerSpec("RLController"), num_vehicles=rl)
    return v


# ------------------------------------------------------------------ possible agents
def test_vehs_per_hour_bound_counts_the_schedule_plus_a_rounding_margin() -> None:
    # 200 veh/h: one every 18 s from t=1; by t=750.5 departures at 1, 19, ..., 739 (42)
    flow = InFlow("inflow_highway", "rl", vehs_per_hour=200)
    assert max_departures(flow, 750.5, 0.5) == 43


def test_number_period_probability_and_late_begin_bound_the_departures() -> None:
    assert max_departures(InFlow("e", "rl", period=10, number=3), 1000, 0.1) == 3
    assert max_departures(InFlow("e", "rl", period=10, end=21), 1000, 0.1) == 4
    # a probability inflow departs at most once per simulation step
    assert max_departures(InFlow("e", "rl", probability=0.1), 11, 0.5) == 22
    assert max_departures(InFlow("e", "rl", period=10, begin=50), 20, 0.1) == 0


def test_possible_agents_are_placed_rl_cars_then_rl_inflow_ids() -> None:
    inflows = InFlows()
    inflows.add(edge="a", veh_type="human", vehs_per_hour=3600)
    inflows.add(edge="a", veh_type="rl", period=5, number=2)
    ids = possible_agent_ids(vehicles(rl=2), inflows, 100.0, 0.5)
    assert ids == ["rl_0", "rl_1", "flow_1.0", "flow_1.1"]
    assert possible_agent_ids(vehicles(rl=0), None, 100.0, 0.5) == []


# ------------------------------------------------------------------ reward formulas
@pytest.mark.parametrize(
    ("r_v", "headway", "speed", "fail", "expected"),
    [
        (0.5, 10.0, 20.0, False, 0.5 + 0.1 * (10 / 20 - 1)),  # 0.45: half the 1 s headway
        (0.5, 30.0, 20.0, False, 0.5),  # 1.5 s headway: no penalty
        (0.5, None, 20.0, False, 0.5),  # no leader: no penalty
        (0.5, 1.0, 0.0, False, 0.5),  # standing: no penalty
        (0.01, 1.0, 20.0, False, 0.0),  # 0.01 - 0.095 clamped at 0
        (0.9, 30.0, 20.0, True, 0.0),  # collision
    ],
)
def test_highway_agent_reward_on_hand_numbers(
    r_v: float, headway: float | None, speed: float, fail: bool, expected: float
) -> None:
    from flowrun.multiagent.highway import highway_agent_reward

    assert highway_agent_reward(r_v, headway, speed, fail) == pytest.approx(expected)


# ------------------------------------------------------------------ registry and CLI
def test_registry_lists_and_resolves_the_multiagent_envs_but_not_for_gymnasium() -> None:
    pytest.importorskip("pettingzoo")
    register_envs()
    for name in MULTIAGENT_ENVS:
        assert name in env_names()
        assert resolve_env_class(name).__name__ == name
        assert f"flowrun/{name}-v0" not in gymnasium.registry
    with pytest.raises(ConfigError, match="did you mean 'MultiAgentMergePOEnv'"):
        resolve_env_class("MultiAgentMergPOEnv")


def test_validate_and_list_accept_the_multiagent_configs() -> None:
    app = typer.Typer()
    register(app)
    runner = CliRunner()
    for name in ("multiagent_ring", "multiagent_merge"):
        result = runner.invoke(app, ["validate", str(CONFIGS / f"{name}.yaml")])
        assert result.exit_code == 0, result.output
        assert "MultiAgent" in result.output
    listed = runner.invoke(app, ["list", "envs"]).output.split()
    assert set(MULTIAGENT_ENVS) <= set(listed)


BLOCK_PETTINGZOO = """
import importlib.abc, sys
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name == "pettingzoo" or name.startswith("pettingzoo."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, Block())
"""


def test_core_imports_without_pettingzoo_and_naming_an_env_says_how_to_install() -> None:
    code = BLOCK_PETTINGZOO + (
        "import flowrun, flowrun.envs, flowrun.multiagent, flowrun.cli.main\n"
        "from flowrun.envs.registry import resolve_env_class\n"
        "from flowrun.errors import ConfigError\n"
        "assert 'pettingzoo' not in sys.modules\n"
        "try:\n"
        "    resolve_env_class('MultiAgentWaveAttenuationPOEnv')\n"
        "except ConfigError as err:\n"
        "    print(err)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout
    assert "PettingZoo is not installed" in out
    assert "pip install 'flowrun[multiagent]'" in out
