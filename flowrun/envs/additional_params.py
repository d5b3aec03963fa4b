"""Checking an env's arguments: its ``additional_params`` against the keys its class
declares, and the network, render mode and parameters it is made with."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from flowrun.config.params import EnvParams, SumoParams
from flowrun.config.validate import check_params
from flowrun.errors import ConfigError, MissingParameterError
from flowrun.suggest import one_edit_apart

if TYPE_CHECKING:
    from flowrun.networks.base import Network


def check_additional_params(cls: type, env_params: EnvParams) -> None:
    """Report a key one edit off a declared or optional one (a typo: Flow's other keys are
    free-form), then every key of ``cls.ADDITIONAL_ENV_PARAMS`` missing from ``env_params``."""
    declared = getattr(cls, "ADDITIONAL_ENV_PARAMS", {}) or {}
    known = [*declared, *(getattr(cls, "OPTIONAL_ENV_PARAMS", {}) or {})]
    for key in env_params.additional_params:
        near = [k for k in known if key not in known and one_edit_apart(str(key), k)]
        if near:
            raise ConfigError(
                f"unknown parameter of {cls.__name__} (did you mean '{near[0]}'?); keys it "
                "does not declare are passed on as they are, but this one looks like a typo",
                path=f"env.additional_params.{key}",
            )
    missing = [k for k in declared if k not in env_params.additional_params]
    if missing:
        keys = ", ".join(f"'{k}' (default there: {declared[k]!r})" for k in missing)
        plural = "s" if len(missing) > 1 else ""
        raise MissingParameterError(
            f"missing key{plural} {keys} that {cls.__name__} declares in its "
            f"ADDITIONAL_ENV_PARAMS; add {'them' if plural else 'it'} to env.additional_params",
            path="env.additional_params",
        )


def check_env_arguments(
    cls: Any,
    env_params: EnvParams,
    sim_params: SumoParams,
    network: Network | None,
    render_mode: str | None,
) -> Network:
    """``network``, once the arguments of an env of class ``cls`` pass the checks a YAML
    config gets (objects built or changed in Python are checked where they are used).

    Raises:
        ConfigError: no network, a render mode ``cls`` does not have, missing or misspelt
            ``additional_params``, or a parameter out of its bounds.
    """
    if network is None:
        raise ConfigError("Env needs a network (network=... or Flow's old scenario=...)")
    if render_mode is not None and render_mode not in cls.metadata["render_modes"]:
        raise ConfigError(f"render_mode {render_mode!r} is not supported; use None or 'rgb_array'")
    check_additional_params(cls, env_params)
    check_params(
        env_params, sim_params, network.net_params, network.initial_config, network.vehicles
    )
    return network
