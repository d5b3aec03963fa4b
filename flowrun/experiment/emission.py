"""``Experiment.run(convert_to_csv=True)``: per-step vehicle states as CSV, as Flow wrote them.

Flow wrote SUMO's emission XML into ``sim_params.emission_path`` and converted it to CSV.
flowrun logs each run to MCAP and exports the CSV from that log
(:func:`flowrun.replay.export.to_csv`, Flow's emission columns), next to it.
"""

from __future__ import annotations

import logging
from datetime import UTC, datetime
from pathlib import Path

from flowrun.config.dump import dump_config
from flowrun.config.model import ExperimentConfig
from flowrun.envs.base import Env
from flowrun.envs.frames import network_metadata
from flowrun.errors import ConfigError
from flowrun.experiment.rundir import unique_dir
from flowrun.recording.writer import McapRecorder

log = logging.getLogger(__name__)


def emission_dir(env: Env, name: str) -> Path:
    """A fresh folder under ``sim_params.emission_path`` for this experiment's logs and CSVs.

    Raises:
        ConfigError: ``emission_path`` is not set (as Flow, which then has nowhere to write).
    """
    base = env.sim_params.emission_path
    if base is None:
        raise ConfigError(
            "convert_to_csv=True needs a folder to write to: set "
            "SumoParams(emission_path='./data') (YAML: sim.emission_path)",
            path="sim.emission_path",
        )
    stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
    return unique_dir(Path(base) / f"{name}-{stamp}")


def run_recorder(
    folder: Path, env: Env, run: int, cfg: ExperimentConfig | None = None
) -> McapRecorder:
    """The MCAP log of run ``run`` in ``folder`` (call after ``env.reset``)."""
    meta = {
        "config_name": cfg.name if cfg is not None else env.network.name,
        "run": str(run),
        "sim_step": repr(env.sim_params.sim_step),
        "sims_per_step": str(env.env_params.sims_per_step),
        "record_every": "1",
        **network_metadata(env.k),
    }
    attachments: dict[str, bytes] = {}
    if cfg is not None:
        meta["config"] = dump_config(cfg)
        attachments["config.yaml"] = meta["config"].encode()
    net_file = getattr(env.k, "net_file", None)
    if net_file is not None:
        attachments["network.net.xml"] = Path(net_file).read_bytes()
    return McapRecorder(folder / f"run_{run}.mcap", metadata=meta, attachments=attachments)


def export_csv(mcap_path: Path) -> Path:
    """Write the CSV of one run's log next to it (``run_0.mcap`` -> ``run_0.csv``)."""
    from flowrun.recording import open_log
    from flowrun.replay.export import to_csv

    out = mcap_path.with_suffix(".csv")
    rows = to_csv(open_log(mcap_path), out)
    log.info("wrote %s (%d rows)", out, rows)
    return out
