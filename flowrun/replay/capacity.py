"""Capacity diagrams of the bottleneck: outflow against inflow over many runs (Flow's
``flow.visualize.capacity_diagram_generator``).

The input is a CSV of ``inflow, outflow`` rows (veh/h), one per simulation, as written by a
sweep over inflow rates; runs at the same inflow are summarised by the mean and standard
deviation of their outflows.
"""

from __future__ import annotations

import argparse
import csv
import os
from typing import Any

import numpy as np

from flowrun.errors import ConfigError


def import_data_from_csv(fp: str | os.PathLike[str]) -> dict[str, list[float]]:
    """``{"inflows": [...], "outflows": [...]}`` (veh/h) from a CSV of ``inflow, outflow`` rows.

    Raises:
        ConfigError: a row that is not two numbers (with its line).
    """
    inflows: list[float] = []
    outflows: list[float] = []
    with open(fp, newline="") as f:
        for line, row in enumerate(csv.reader(f), 1):
            if not row:
                continue
            try:
                inflow, outflow = float(row[0]), float(row[1])
            except (IndexError, ValueError):
                raise ConfigError(
                    f"expected 'inflow, outflow' (two numbers, veh/h), got {row!r}",
                    "",
                    f"{fp}:{line}",
                ) from None
            inflows.append(inflow)
            outflows.append(outflow)
    return {"inflows": inflows, "outflows": outflows}


def get_capacity_data(data: dict[str, Any]) -> tuple[list[float], np.ndarray, np.ndarray]:
    """The distinct inflows (sorted) and the mean and standard deviation of the outflows
    measured at each, veh/h."""
    by_inflow: dict[float, list[float]] = {}
    for inflow, outflow in zip(data["inflows"], data["outflows"], strict=True):
        by_inflow.setdefault(float(inflow), []).append(float(outflow))
    inflows = sorted(by_inflow)
    mean = np.asarray([np.mean(by_inflow[x]) for x in inflows])
    std = np.asarray([np.std(by_inflow[x]) for x in inflows])
    return inflows, mean, std


def create_parser() -> argparse.ArgumentParser:
    """Flow's command-line parser of the capacity diagram script (one CSV path)."""
    parser = argparse.ArgumentParser(
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="[Flow] Generates capacity diagrams for the bottleneck.",
        epilog="python capacity_diagram_generator.py </path/to/file>.csv",
    )
    parser.add_argument("file", type=str, help="path to the csv file.")
    return parser
