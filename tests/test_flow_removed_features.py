"""What Flow itself removed or tolerates, handled as Flow does: ``NetParams(no_internal_links)``
(gone since 2019), ``lanes_distribution`` below 1 (counted as 1, with a warning),
``flow.utils.flow_warnings.deprecation_warning`` (Flow's message)."""

from __future__ import annotations

import logging
import warnings

import numpy as np
import pytest

from flowrun.config.params import InitialConfig, NetParams
from flowrun.config.validate import check_params
from flowrun.errors import ConfigError
from flowrun.networks.placement import place_on_closed_road
from flowrun.utils.flow_warnings import deprecation_warning


def test_no_internal_links_false_is_what_flowrun_does_and_only_warns() -> None:
    with pytest.warns(DeprecationWarning, match="removed by Flow in 2019"):
        net = NetParams(no_internal_links=False, additional_params={"radius_ring": 30})
    # the object is the one built without the keyword
    assert net.__dict__ == NetParams(additional_params={"radius_ring": 30}).__dict__
    assert "no_internal_links" not in net.__dict__


def test_no_internal_links_true_is_refused_with_the_fix() -> None:
    with pytest.raises(ConfigError, match="remove the argument") as err:
        NetParams(no_internal_links=True)
    assert err.value.path == "net.no_internal_links"


def test_other_unknown_keywords_still_fail_as_python_does() -> None:
    with pytest.raises(TypeError, match="unexpected keyword argument 'no_such'"):
        NetParams(no_such=1)  # type: ignore[call-arg]


@pytest.mark.parametrize("value", [0, 0.5, -3, -100, -np.inf])
def test_lanes_distribution_below_one_places_every_car_on_one_lane(
    value: float, caplog: pytest.LogCaptureFixture
) -> None:
    initial = InitialConfig(lanes_distribution=value)
    check_params(initial)  # accepted, as Flow accepts it
    with caplog.at_level(logging.WARNING, logger="flowrun.networks.placement"):
        _, lanes = place_on_closed_road(230.0, 4, [7.5] * 12, initial,
                                        np.random.default_rng(0))  # fmt: skip
    assert lanes == [0] * 12
    assert "lanes_distribution" in caplog.text and "setting to 1" in caplog.text


def test_lanes_distribution_nan_is_still_refused() -> None:
    with pytest.raises(ConfigError, match="must be a number"):
        check_params(InitialConfig(lanes_distribution=float("nan")))


def test_lanes_distribution_above_the_lane_count_uses_every_lane() -> None:
    _, lanes = place_on_closed_road(230.0, 3, [7.5] * 6, InitialConfig(lanes_distribution=9),
                                    np.random.default_rng(0))  # fmt: skip
    assert lanes == [0, 1, 2, 0, 1, 2]


def test_deprecation_warning_says_what_flow_says() -> None:
    class Foo:
        pass

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        deprecation_warning(Foo(), "bar_deprecated", "bar_new")
    assert [type(w.message) for w in caught] == [UserWarning]
    assert str(caught[0].message) == (
        "The attribute bar_deprecated in Foo is deprecated, use bar_new instead."
    )
