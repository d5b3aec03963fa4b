"""Flow compatibility: re-exports. Flow's ``flow.core.util`` path.

``emission_to_csv`` and ``ensure_dir`` live in :mod:`flowrun.experiment.emission`.
"""

from flowrun.experiment.emission import EMISSION_CSV_COLUMNS, emission_to_csv, ensure_dir

__all__ = ["EMISSION_CSV_COLUMNS", "emission_to_csv", "ensure_dir"]
