"""A saved multi-robot learner (``ippo-<variant>_seed<N>.zip``, ``mappo-…``) as the policy of
every robot of the PettingZoo env in the evaluation (`baselines.policy.MultiPolicy`, found by
`bounce_gym_experiments.families.base.Family.trained_policies` beside the SB3 models).

Execution is decentralised: each robot acts from its own observation through its actor (the
one actor, when shared) — never from ``infos``, and never from the global state, which only
MAPPO's critic saw in training (the critics are read from the file with the actors, their
shapes checked, and left unused). As `baselines.rl.policies.SharedSB3Policy`, each robot's action
is **sampled** from its categorical distribution by default, with a generator restarted from the
episode's seed (`baselines.rl.action_draws.episode_stream`); ``deterministic=True`` plays each
robot's most likely action instead. The weights are read as data (`baselines.rl.jaxrl.weights`:
an ``.npz`` without pickle, every size checked before anything is inflated).

`TeamPolicy.described` names what the row plays: the algorithm, the sharing and what the
observation carries besides contact and clock, e.g. ``mappo (shared, id)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from baselines.policy import MultiPolicy, is_parallel_env
from baselines.rl.action_draws import categorical, episode_stream
from baselines.rl.jaxrl.weights import read_weights, saved_config
from baselines.rl.marl.networks import TeamNetworks, critic_size, load_weights, weight_shapes
from baselines.rl.marl.settings import SHARING_VARIANTS, settings
from baselines.rl.model_files import MARL_ALGOS, read_model
from baselines.rl.policies import GREEDY_SUFFIX
from bounce_gym.errors import ConfigError


def observed(options) -> list[str]:
    """What a robot's observation carries besides contact and clock, in a row's words."""
    out = ["id"] if options.agent_id else []
    if options.history:
        out.append(f"history {options.history}")
    if options.privileged:
        out.append("pose")
    return out


class TeamPolicy(MultiPolicy):
    """An ippo or mappo model file as the policy of every robot of the parallel env ``env``."""

    def __init__(self, path: Path, env, deterministic: bool = False) -> None:
        if not is_parallel_env(env):
            raise ConfigError(f"model {path}: a multi-robot learner acts in a PettingZoo "
                              "parallel env")
        trained = read_model(path)
        if trained.algo not in MARL_ALGOS:
            raise ConfigError(f"model {path}: not a multi-robot learner's model "
                              f"({'/'.join(MARL_ALGOS)})")
        config = saved_config(trained)
        chosen = settings(config["hyperparams"], config["n_envs"])
        self.agents = list(env.possible_agents)
        m = len(self.agents)
        spaces = [env.observation_space(a) for a in self.agents]
        counts = {int(env.action_space(a).n) for a in self.agents}
        if len(counts) != 1 or len(spaces[0].shape) != 1:
            raise ConfigError(f"model {path}: its robots need flat observations and the same "
                              f"number of actions each, this env's have {sorted(counts)}")
        n_obs = self.n_obs = int(spaces[0].shape[0])
        self.nets = TeamNetworks(chosen, m, n_obs,
                                 critic_size(trained.algo, chosen.share, n_obs, m), counts.pop())
        load_weights(self.nets, read_weights(trained, weight_shapes(self.nets)))
        self.nets.eval()
        self.deterministic = deterministic
        self.rng: np.random.Generator | None = None
        variant = trained.path.stem.partition("_seed")[0].partition("-")[2]
        run = trained.algo if variant in SHARING_VARIANTS.values() \
            else f"{trained.algo}-{variant}"
        seen = observed(env.unwrapped.options)
        #: the row's words: algorithm, sharing, what the robots observe
        self.described = f"{run} ({', '.join([SHARING_VARIANTS[chosen.share], *seen])})"
        self.name = f"rl {self.described}{GREEDY_SUFFIX if deterministic else ''}"

    def start_options(self, env, seed: int) -> None:
        self.rng = episode_stream(seed)
        return None

    def act(self, observations, infos):
        """Each live robot's action from its own observation (``infos`` is not read)."""
        m = len(self.agents)
        live = [a for a in self.agents if a in observations]
        x = np.zeros((m, self.n_obs), dtype=np.float32)
        for a in live:
            x[self.agents.index(a)] = observations[a]
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # m tiny rows: intra-op threads only add overhead
        try:
            with torch.no_grad():
                probs = torch.softmax(self.nets.logits(torch.from_numpy(x)), -1).numpy()
        finally:
            torch.set_num_threads(threads)
        rows = np.array([self.agents.index(a) for a in live], dtype=np.int64)
        if self.deterministic:
            actions = probs[rows].argmax(axis=1)
        elif self.rng is None:
            raise RuntimeError(f"{self.name}: start_options(env, seed) starts an episode of a "
                               "sampling policy (baselines.policy.Policy)")
        else:
            actions = categorical(probs[rows].astype(np.float64), self.rng)
        return {a: int(act) for a, act in zip(live, actions, strict=True)}
