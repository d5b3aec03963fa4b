"""Flow's benchmark experiments as Python values, read from their files in ``configs/``.

The envs' own default experiments are the files their classes name
(:func:`flowrun.envs.factory.default_experiment`); this module serves code that wants the
same experiments as values: :func:`merge0_config` (``configs/merge.yaml``) and
:func:`grid_config`, Flow's grid benchmark (``configs/grid0.yaml``) on a grid of any size.
"""

from __future__ import annotations

from dataclasses import replace

from flowrun.config.model import ExperimentConfig, NetworkConfig
from flowrun.config.params import InFlows, NetParams, VehicleParams
from flowrun.envs.factory import CONFIGS_DIR
from flowrun.loading.loader import load_config

#: Flow's grid benchmarks: inflow per entry edge (veh/h), entry speed (m/s) (``grid0.yaml``).
EDGE_INFLOW, V_ENTER = 300, 30


def merge0_config() -> ExperimentConfig:
    """Flow's merge benchmark merge0 (``configs/merge.yaml``; merge1/2 are in
    ``configs/benchmarks/``)."""
    return load_config(CONFIGS_DIR / "merge.yaml")


def entry_edges(rows: int, cols: int) -> list[str]:
    """The grid's entry edges in Flow's order (from the top, bottom, left, right)."""
    return (
        [f"left{rows}_{j}" for j in range(cols)]
        + [f"right0_{j}" for j in range(cols)]
        + [f"bot{i}_0" for i in range(rows)]
        + [f"top{i}_{cols}" for i in range(rows)]
    )


def grid_config(
    rows: int = 3, cols: int = 3, env_class: str = "TrafficLightGridBenchmarkEnv"
) -> ExperimentConfig:
    """Flow's grid benchmark on a ``rows`` x ``cols`` grid: ``configs/grid0.yaml`` (3 x 3)
    with its grid resized, one car placed and one inflow (as the file's first) on each entry
    edge (grid1, 5 x 5, is ``configs/grid1.yaml``)."""
    cfg = load_config(CONFIGS_DIR / "grid0.yaml")
    net = cfg.network.net_params
    grid = {**net.additional_params["grid_array"], "row_num": rows, "col_num": cols}
    flow = net.inflows.get()[0] if net.inflows is not None else None
    if flow is None:
        raise ValueError("configs/grid0.yaml has no inflow to copy")
    inflows = InFlows([replace(flow, edge=edge) for edge in entry_edges(rows, cols)])
    network = NetworkConfig(
        cfg.network.type,
        NetParams({**net.additional_params, "grid_array": grid}, inflows=inflows),
    )
    (human,) = cfg.vehicles.groups
    vehicles = VehicleParams([replace(human, num_vehicles=2 * cols + 2 * rows)])
    return replace(
        cfg,
        name="grid0" if (rows, cols) == (3, 3) else f"grid_{rows}x{cols}",
        env=replace(cfg.env, env_class=env_class),
        network=network,
        vehicles=vehicles,
    )
