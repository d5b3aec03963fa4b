"""What a policy's evaluation is compared with: the benchmark's own baseline, else all-human.

For one of Flow's benchmarks (the config's ``name:`` is a key of
:data:`~flowrun.experiment.benchmark.BENCHMARKS`) the baseline is the one ``flowrun benchmark``
and the README's results table use: the benchmark's ``--set`` overrides applied to the config
(14 human drivers of the paper's vehicle type for the figure eights, SUMO's actuated lights for
the grids, the whole inflow human for the merges and bottlenecks; evaluate mode). For any other
config it is the same config with every RL vehicle group driven like the first human group.
``flowrun eval`` (SB3 and RLlib runs) and the evaluations during training both take it from
:func:`comparison_baseline`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import yaml

from flowrun.config.dump import config_to_dict
from flowrun.config.model import ExperimentConfig
from flowrun.config.overrides import apply_overrides
from flowrun.config.params import VehicleParams, is_rl
from flowrun.config.yamlio import Locations, parse_yaml
from flowrun.errors import ConfigError
from flowrun.experiment.benchmark import BENCHMARKS, Benchmark
from flowrun.loading.loader import config_from_dict, read_config_text

ALL_HUMAN = "all-human"
BENCHMARK = "benchmark"


@dataclass(frozen=True)
class Comparison:
    """The rollout a policy is compared with.

    Attributes:
        config: its config (same seeds as the policy's episodes).
        kind: ``benchmark`` (a benchmark's own baseline) or ``all-human``.
        description: one line saying which baseline it is.
        benchmark: the benchmark whose baseline it is, or ``None`` (all-human).
    """

    config: ExperimentConfig
    kind: str
    description: str
    benchmark: str | None = None

    @property
    def label(self) -> str:
        """Its row label in tables: ``baseline`` (a benchmark's own) or ``all-human``."""
        return "baseline" if self.kind == BENCHMARK else ALL_HUMAN


def all_human(cfg: ExperimentConfig) -> ExperimentConfig:
    """The config with each RL group driven like the first human group."""
    humans = [g for g in cfg.vehicles.groups if not is_rl(g)]
    if not humans:
        raise ConfigError("no human vehicle group to copy for the all-human baseline", "vehicles")
    human = humans[0].acceleration_controller
    groups = [
        replace(g, acceleration_controller=human) if is_rl(g) else g for g in cfg.vehicles.groups
    ]
    return replace(cfg, vehicles=VehicleParams(groups))


def all_human_or_none(cfg: ExperimentConfig) -> ExperimentConfig | None:
    """:func:`all_human` of ``cfg``; ``None`` when every group is RL (no human to copy)."""
    try:
        return all_human(cfg)
    except ConfigError:
        return None


def benchmark_of(cfg: ExperimentConfig) -> Benchmark | None:
    """The benchmark ``cfg`` is (by its ``name:``), or ``None``."""
    return BENCHMARKS.get(cfg.name)


def benchmark_baseline(cfg: ExperimentConfig, bench: Benchmark) -> ExperimentConfig:
    """``cfg`` with the benchmark's baseline overrides applied, as ``flowrun benchmark``
    applies them to the benchmark's file (after the user's ``--set`` values).

    Raises:
        ConfigError: the overrides do not fit ``cfg`` (a config named like a benchmark but
            built otherwise), naming the benchmark and its overrides.
    """
    if cfg.network.type != bench.network_type:
        raise ConfigError(
            f"this config is named {bench.name}, but its network is {cfg.network.type!r}, not "
            f"the benchmark's {bench.network_type!r}; rename the config (name:) to compare with "
            "its all-human version instead",
            "network.type",
            _location(cfg, ("network", "type")),
        )
    data = config_to_dict(cfg)
    source = cfg.source or "<config>"
    try:
        apply_overrides(data, bench.baseline, Locations(source))
        return replace(config_from_dict(data, source), source=cfg.source)
    except ConfigError as err:
        sets = " ".join(f"--set {s!r}" for s in bench.baseline)
        raise ConfigError(
            f"this config is named {bench.name}, but the benchmark's baseline ({sets}) does "
            f"not fit it: {err.message}; rename the config (name:) to compare with its "
            "all-human version instead",
            err.path,
            err.location,
        ) from None


def _location(cfg: ExperimentConfig, path: tuple[str, ...]) -> str:
    """``file:line`` of ``path`` in the YAML file ``cfg`` was loaded from, else its source."""
    source = cfg.source or "<config>"
    try:
        return parse_yaml(read_config_text(Path(source), source), source)[1].of(path)
    except (ConfigError, yaml.YAMLError):
        return source


def comparison_baseline(cfg: ExperimentConfig) -> Comparison | None:
    """What a policy trained on ``cfg`` is compared with: the benchmark's own baseline for
    one of Flow's benchmarks, else the all-human config; ``None`` when there is none (every
    vehicle group RL in a config that is no benchmark)."""
    bench = benchmark_of(cfg)
    if bench is not None:
        note = f"the benchmark's own baseline ({bench.name}: {bench.baseline_note})"
        return Comparison(benchmark_baseline(cfg, bench), BENCHMARK, note, bench.name)
    human = all_human_or_none(cfg)
    if human is None:
        return None
    note = "all-human: every RL vehicle driven like the first human group"
    return Comparison(human, ALL_HUMAN, note)
