"""A trained SB3 model's deterministic policy as a plain function ``obs -> action``.

:func:`policy_act` copies a plain MLP policy into numpy (a few microseconds a step instead of
SB3's ~100-250 µs ``predict``) and falls back to SB3's ``predict`` for any other policy.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from flowrun.training.deps import require

if TYPE_CHECKING:
    from stable_baselines3.common.base_class import BaseAlgorithm

# obs (1-D, already normalised) -> action; a batch of observations (rows) -> actions (rows)
Act = Callable[[np.ndarray], np.ndarray]


def numpy_policy(policy: Any) -> Act | None:
    """The deterministic action of an SB3 ``ActorCriticPolicy`` MLP, computed with numpy.

    Returns ``None`` when the policy is not a plain one (not a flattened Box observation, not
    Linear/Tanh/ReLU layers, a squashed or non-Gaussian action): use :func:`torch_policy`.
    The weights are copied, so later training does not change the returned function.
    """
    torch = require("torch")
    nn = torch.nn
    distributions = require("stable_baselines3.common.distributions")
    torch_layers = require("stable_baselines3.common.torch_layers")
    mlp = getattr(policy, "mlp_extractor", None)
    action_net = getattr(policy, "action_net", None)
    if (
        mlp is None
        or not isinstance(action_net, nn.Linear)
        or getattr(policy, "squash_output", True)
        or not isinstance(policy.action_dist, distributions.DiagGaussianDistribution)
        or not isinstance(policy.pi_features_extractor, torch_layers.FlattenExtractor)
    ):
        return None
    layers: list[tuple[str, np.ndarray | None, np.ndarray | None]] = []
    for module in [*mlp.policy_net, action_net]:
        if isinstance(module, nn.Linear):
            weight = module.weight.detach().cpu().numpy().astype(np.float64).T.copy()
            bias = module.bias.detach().cpu().numpy().astype(np.float64).copy()
            layers.append(("linear", weight, bias))
        elif isinstance(module, nn.Tanh | nn.ReLU):
            layers.append((type(module).__name__.lower(), None, None))
        else:
            return None
    low = np.asarray(policy.action_space.low, dtype=np.float64)
    high = np.asarray(policy.action_space.high, dtype=np.float64)

    def act(obs: np.ndarray) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float64)  # one observation, or a batch (rows)
        for kind, weight, bias in layers:
            if kind == "linear":
                x = x @ weight + bias  # type: ignore[operator]
            elif kind == "tanh":
                x = np.tanh(x)
            else:
                x = np.maximum(x, 0.0)
        return np.clip(x, low, high).astype(np.float32)

    return act


def torch_policy(model: BaseAlgorithm) -> Act:
    """SB3's own deterministic ``predict`` (any policy; slower per step)."""

    def act(obs: np.ndarray) -> np.ndarray:
        action, _ = model.predict(obs, deterministic=True)
        return np.asarray(action)

    return act


def policy_act(model: BaseAlgorithm) -> Act:
    """The fastest faithful deterministic policy of ``model`` (numpy copy, else SB3's)."""
    return numpy_policy(model.policy) or torch_policy(model)
