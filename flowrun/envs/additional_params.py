"""Checking an env's ``additional_params`` against the keys its class declares."""

from __future__ import annotations

from flowrun.config.params import EnvParams
from flowrun.errors import ConfigError, MissingParameterError
from flowrun.suggest import one_edit_apart


def check_additional_params(cls: type, env_params: EnvParams) -> None:
    """Report a key one edit off a declared one (a typo: Flow's other keys are free-form),
    then every key of ``cls.ADDITIONAL_ENV_PARAMS`` missing from ``env_params``."""
    declared = getattr(cls, "ADDITIONAL_ENV_PARAMS", {}) or {}
    for key in env_params.additional_params:
        near = [k for k in declared if key not in declared and one_edit_apart(str(key), k)]
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
