"""Flow compatibility: re-exports. Flow's ``flow.core.util`` path.

``emission_to_csv`` and ``ensure_dir`` live in :mod:`flowrun.experiment.emission`,
``makexml`` and ``printxml`` in :mod:`flowrun.networks.xml_files`.
"""

from flowrun.experiment.emission import EMISSION_CSV_COLUMNS, emission_to_csv, ensure_dir
from flowrun.networks.xml_files import makexml, printxml

__all__ = ["EMISSION_CSV_COLUMNS", "emission_to_csv", "ensure_dir", "makexml", "printxml"]
