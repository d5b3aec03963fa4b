"""Flow's pyglet render modes (``SumoParams(render="drgb")``, ``rgb``, ``dgray``, ``gray``) are
accepted: they run headless and the env draws its frames with flowrun's painter
(``env.render()``), grey for the gray modes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flowrun.core.params import SumoParams
from flowrun.errors import ConfigError
from flowrun.loading.loader import load_config
from flowrun.utils.registry import env_constructor
from tests.test_flow_params import ring_params

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.sumo
@pytest.mark.parametrize("mode", ["drgb", "rgb", "dgray", "gray"])
def test_a_frame_mode_draws_a_frame_every_step(mode: str) -> None:
    env = env_constructor(ring_params(sim=SumoParams(sim_step=0.1, render=mode)))()
    try:
        assert env.render_mode == "rgb_array" and not env.k.gui
        env.reset(seed=0)
        env.step(None)
        frame = env.render()
        assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
        grey = bool((frame == frame[..., :1]).all())  # the three channels equal
        assert grey == mode.endswith("gray")
        assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 2  # road and cars, not a blank
    finally:
        env.close()


def test_yaml_takes_the_modes_and_refuses_others(tmp_path: Path) -> None:
    text = (ROOT / "configs" / "sugiyama.yaml").read_text()
    assert "render: false" in text
    path = tmp_path / "r.yaml"
    path.write_text(text.replace("render: false", "render: dgray"))
    assert load_config(path).sim.render == "dgray"
    path.write_text(text.replace("render: false", "render: dgrey"))
    with pytest.raises(ConfigError, match="did you mean 'dgray'") as info:
        load_config(path)
    assert info.value.path == "sim.render"
