"""Loading an experiment: a YAML file (or Flow's ``flow_params``) into a checked config.

:mod:`flowrun.config` holds the vocabulary (parameter types, YAML reading); loading sits
above :mod:`flowrun.networks` because its checks build the config's network (edges, routes,
traffic-light programs, the initial placement). :mod:`~flowrun.preflight.checks` holds what
``baseline``/``train``/``validate`` check before a run starts.
"""

from flowrun.loading.loader import config_from_dict, load_config

__all__ = ["config_from_dict", "load_config"]
