"""Flow's ``v_eq_max_function`` (``flow.envs.ring.wave_attenuation``): solved for the speed,
it gives Flow's equilibrium speeds of a 22-car ring with one AV."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import fsolve

from flowrun.envs.ring.wave_attenuation import v_eq_max_function


@pytest.mark.parametrize(("length", "speed"), [(230, 3.7136148111012934),
                                               (270, 5.6143732387852054)])  # fmt: skip
def test_the_root_is_flows_equilibrium_speed(length: int, speed: float) -> None:
    root = float(fsolve(v_eq_max_function, np.array([4.0]), args=(22, length))[0])
    assert root == pytest.approx(speed, abs=1e-9)


def test_the_residual_is_the_largest_gap_minus_idms_equilibrium_gap() -> None:
    # 22 cars on 230 m: largest gap (230 - 110) / 21; IDM's gap at 0 m/s is s0 = 2 m
    assert v_eq_max_function(0.0, 22, 230) == pytest.approx(120 / 21 - 2.0)
    assert np.shape(v_eq_max_function(np.array([1.0, 2.0]), 22, 230)) == (2,)
