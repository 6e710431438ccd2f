"""The actors and critics of a team of m robots: MLPs with Stable-Baselines3's orthogonal
initialisation (gain √2 for the hidden layers, 0.01 for the actor's head, 1 for the critic's;
biases zero), one of each for every robot (``share: false``) or one of each for all of them
(``share: true``), and what each critic sees (`critic_input`).

Their weights leave and enter torch as named float32 arrays (`weights`, `load_weights`: the
names of the module's ``state_dict``), the form a model file keeps them in
(`baselines.rl.jaxrl.weights`: an ``.npz`` read without pickle).
"""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import nn

from baselines.rl.marl.settings import Settings

#: The gain of the hidden layers' orthogonal initialisation.
HIDDEN_GAIN = math.sqrt(2.0)
_ACTIVATIONS = {"tanh": nn.Tanh, "relu": nn.ReLU}


def mlp(n_in: int, hidden: list[int], n_out: int, activation: str, head_gain: float
        ) -> nn.Sequential:
    """``n_in -> hidden... -> n_out``, the activation after every layer but the last."""
    layers: list[nn.Module] = []
    sizes = [n_in, *hidden, n_out]
    for k, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
        linear = nn.Linear(a, b)
        last = k == len(sizes) - 2
        nn.init.orthogonal_(linear.weight, gain=head_gain if last else HIDDEN_GAIN)
        nn.init.zeros_(linear.bias)
        layers.append(linear)
        if not last:
            layers.append(_ACTIVATIONS[activation]())
    return nn.Sequential(*layers)


def critic_size(algo: str, share: bool, n_obs: int, n_robots: int) -> int:
    """The length of a critic's input (`critic_input`)."""
    if algo == "ippo":
        return n_obs
    return 4 * n_robots + (n_robots if share else 0)


def critic_input(algo: str, share: bool, obs: np.ndarray, state: np.ndarray | None
                 ) -> np.ndarray:
    """What every robot's critic sees, (..., m, c) float32, from the observations (..., m, d)
    and the global states (..., 4m): IPPO the robot's own observation; MAPPO the state, with the
    robot's one-hot index when one critic serves every robot."""
    if algo == "ippo":
        return obs
    m = obs.shape[-2]
    seen = np.broadcast_to(state[..., None, :], (*obs.shape[:-1], state.shape[-1]))
    if share:
        seen = np.concatenate((seen, np.broadcast_to(np.eye(m, dtype=np.float32),
                                                     (*obs.shape[:-2], m, m))), axis=-1)
    return np.ascontiguousarray(seen, dtype=np.float32)


class TeamNetworks(nn.Module):
    """The actors and critics of m robots, applied to inputs (..., m, features): robot i's
    row goes through robot i's network (the only one, when shared)."""

    def __init__(self, settings: Settings, n_robots: int, n_obs: int, n_critic: int,
                 n_actions: int) -> None:
        super().__init__()
        self.share = settings.share
        self.n_robots = n_robots
        copies = 1 if settings.share else n_robots
        act = settings.activation
        self.actors = nn.ModuleList(mlp(n_obs, settings.actor_layers, n_actions, act, 0.01)
                                    for _ in range(copies))
        self.critics = nn.ModuleList(mlp(n_critic, settings.critic_layers, 1, act, 1.0)
                                     for _ in range(copies))

    def _each(self, nets: nn.ModuleList, x: torch.Tensor) -> torch.Tensor:
        if self.share:
            return nets[0](x)
        return torch.stack([net(x[..., i, :]) for i, net in enumerate(nets)], dim=-2)

    def logits(self, x: torch.Tensor) -> torch.Tensor:
        """(..., m, actions) from observations (..., m, d)."""
        return self._each(self.actors, x)

    def values(self, x: torch.Tensor) -> torch.Tensor:
        """(..., m) from critic inputs (..., m, c)."""
        return self._each(self.critics, x)[..., 0]

    def groups(self) -> list[list[nn.Parameter]]:
        """The parameters whose gradient is clipped together: each robot's actor and critic
        (all of them when shared)."""
        return [[*a.parameters(), *c.parameters()]
                for a, c in zip(self.actors, self.critics, strict=True)]


def weights(nets: nn.Module) -> dict[str, np.ndarray]:
    """The module's weights as named float32 arrays (copies)."""
    return {name: value.detach().numpy().astype(np.float32, copy=True)
            for name, value in nets.state_dict().items()}


def weight_shapes(nets: nn.Module) -> dict[str, tuple[int, ...]]:
    """The name and shape of every array `weights` gives."""
    return {name: tuple(value.shape) for name, value in nets.state_dict().items()}


def load_weights(nets: nn.Module, arrays: dict[str, np.ndarray]) -> None:
    """Put arrays of `weight_shapes`'s names and shapes into the module."""
    nets.load_state_dict({name: torch.from_numpy(array) for name, array in arrays.items()})
