"""ARS's candidates acting with a numpy copy of their policy in sb3-contrib's ``AsyncEval``.

``AsyncEval``'s workers load each candidate's weights into the policy
(``load_from_vector``) and run ``evaluate_policy``, which calls ``policy.predict`` at every
step: about 0.1 ms of torch for a linear policy, as long as a figure-eight step. A
:class:`NumpyPredictor` given to ``AsyncEval`` instead of the policy loads the weights into the
torch policy and into a numpy copy, and answers ``predict`` with the copy (the torch policy
when the copy cannot be made: a discrete action space, a layer other than Linear, Tanh, ReLU).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from flowrun.training.deps import require
from flowrun.training.rollout import Mlp

ACTIVATIONS = {"Tanh": "tanh", "ReLU": "relu"}


def mlp_of(modules: list[Any]) -> Mlp | None:
    """The numpy copy of a sequence of torch ``Linear`` / ``Tanh`` / ``ReLU`` modules (a
    ``Linear`` without bias gets a zero one), or ``None`` for any other sequence."""
    nn = require("torch").nn
    weights: list[np.ndarray] = []
    biases: list[np.ndarray] = []
    activations: list[str] = []
    for module in modules:
        if isinstance(module, nn.Linear):
            weight = module.weight.detach().cpu().numpy().astype(np.float64)
            weights.append(weight.T.copy())
            bias = module.bias
            biases.append(np.zeros(weight.shape[0]) if bias is None
                          else bias.detach().cpu().numpy().astype(np.float64).copy())
            activations.append("")
        elif type(module).__name__ in ACTIVATIONS and activations and not activations[-1]:
            activations[-1] = ACTIVATIONS[type(module).__name__]
        else:
            return None
    return Mlp(tuple(weights), tuple(biases), tuple(activations)) if weights else None


class NumpyPredictor:
    """An ARS policy's ``predict`` in numpy, for ``AsyncEval``'s workers (picklable).

    Args:
        policy: sb3-contrib's ``ARSPolicy`` (``LinearPolicy`` or ``MlpPolicy``).
    """

    def __init__(self, policy: Any) -> None:
        self.policy = policy
        self._net: Mlp | None = None
        self._refresh()

    def load_from_vector(self, vector: Any) -> None:
        """Load a candidate's weights (as ``BasePolicy.load_from_vector``)."""
        self.policy.load_from_vector(vector)
        self._refresh()

    def _refresh(self) -> None:
        spaces = require("gymnasium").spaces
        torch_layers = require("stable_baselines3.common.torch_layers")
        policy = self.policy
        box = isinstance(policy.action_space, spaces.Box)
        flat = isinstance(policy.features_extractor, torch_layers.FlattenExtractor)
        net = getattr(policy, "action_net", None)
        self._net = mlp_of(list(net)) if box and flat and net is not None else None

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
    ) -> tuple[np.ndarray, Any]:
        """``BasePolicy.predict``: the action for one observation or a batch of them."""
        if self._net is None or isinstance(observation, dict):
            return self.policy.predict(
                observation, state, episode_start, deterministic)
        space = self.policy.action_space
        obs = np.asarray(observation)
        batch = obs.reshape(-1, *self.policy.observation_space.shape)
        actions = self._net(batch.reshape(batch.shape[0], -1))
        if self.policy.squash_output:  # tanh output scaled to the bounds (unscale_action)
            actions = space.low + 0.5 * (actions + 1.0) * (space.high - space.low)
        else:
            actions = np.minimum(np.maximum(actions, space.low), space.high)
        actions = actions.astype(space.dtype).reshape((-1, *space.shape))
        if obs.shape == self.policy.observation_space.shape:
            actions = actions[0]  # one observation, one action
        return actions, None
