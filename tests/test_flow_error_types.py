"""flowrun's errors are also the builtin exception types Flow raises for the same mistakes,
so Flow code that catches ``KeyError`` / ``AssertionError`` keeps working."""

from __future__ import annotations

import pytest

from flowrun.core.params import EnvParams, NetParams, SumoParams, VehicleParams
from flowrun.envs.ring.accel import ADDITIONAL_ENV_PARAMS, AccelEnv
from flowrun.errors import ConfigError, CountMismatchError, MissingParameterError
from flowrun.networks import RingNetwork


def ring() -> RingNetwork:
    vehicles = VehicleParams()
    vehicles.add("human", num_vehicles=2)
    return RingNetwork("r", vehicles, NetParams(additional_params={"length": 230}))


@pytest.mark.parametrize("key", sorted(ADDITIONAL_ENV_PARAMS))
def test_each_missing_env_param_is_a_key_error_and_a_config_error(key: str) -> None:
    given = {k: v for k, v in ADDITIONAL_ENV_PARAMS.items() if k != key}
    with pytest.raises(KeyError) as err:
        AccelEnv(EnvParams(additional_params=given), SumoParams(), ring())
    assert isinstance(err.value, ConfigError)
    assert isinstance(err.value, MissingParameterError)
    assert f"'{key}'" in str(err.value)
    assert not str(err.value).startswith('"')  # the message itself, not KeyError's repr


def test_all_env_params_given_builds_the_env() -> None:
    env = AccelEnv(EnvParams(additional_params=dict(ADDITIONAL_ENV_PARAMS)), SumoParams(), ring())
    try:
        assert env.env_params.additional_params == ADDITIONAL_ENV_PARAMS
        assert env.initial_vehicles.num_vehicles == 2
    finally:
        env.close()


def test_count_mismatch_is_an_assertion_error() -> None:
    err = CountMismatchError("3 vs 15", path="edges_distribution")
    assert isinstance(err, AssertionError) and isinstance(err, ConfigError)
    assert str(err) == "edges_distribution: 3 vs 15"
