"""A fleet of profiling drifters covering the surface, as a PettingZoo parallel environment.

| | |
|---|---|
| Import | ``pettingzoo.make("parallel", "bounce_gym/MultiDrifter-v0")`` or ``from bounce_gym.envs.drifters import multi_drifter_v0`` (``parallel_env()``, ``env()``) |
| Agents | ``drifter_0`` … ``drifter_{n-1}`` |

## Description

n drifters are deployed at chosen cells (thesis ch. 5, problem 1: deployment cells whose
drifters visit every surface cell) and carried by the currents; each can rise, sink or drift
(`DrifterEnv` has the details, backends and arguments). All act at once every step. The
**AEC form** (``env()``) is PettingZoo's ``parallel_to_aec`` conversion of this env: the
drifters choose in turn and the fleet moves once all have chosen; each action is checked
(`check_action`) as it is given.

## Action Space

Per drifter, ``Discrete(3)`` as `DrifterEnv`'s: 0 drift, 1 up (one layer shallower), 2 down
(one layer deeper); an illegal move drifts instead (its info's ``action_mask`` and
``illegal_action``).

## Observation Space

Per drifter, a ``Box(0, 1)`` of float32: its layer and the clock (steps / ``max_cycles``), then
optionally its last surface fix and the true position (`bounce_gym.envs.drifters.core`).
``state()`` is every drifter's (x, y, layer), each in [0, 1].

## Rewards

Shared surface coverage: the number of surface cells that some drifter visits for the first
time in the step (a drifter is at the surface and in that cell at the end of the step; the
deployment cells count as visited at reset), split evenly over the drifters.
``info["coverage"]`` is the fraction of surface water cells visited so far.

## Starting State

Each drifter in a surface water cell drawn at random, distinct cells while there are enough,
unless ``deploy`` (or ``reset(options={"deploy": [...]})``) gives each its region.

## Episode End

All drifters terminate when the whole surface is visited; all are truncated after
``max_cycles`` steps.

## Arguments

``max_cycles`` (default 500), ``render_mode``, ``field_style``, then the keyword arguments
declared in `bounce_gym.envs.drifters.options.DrifterOptions` but the single drifter's task,
regions and clock (`SINGLE_ONLY`): the flow, backend and sensing arguments of `DrifterEnv`,
``n_drifters`` (default 4, or the length of a ``deploy`` list) and ``deploy`` (per episode also
with ``reset(options={"deploy": [...]})``); each argument's type, default and meaning are in
the signature of the class and the "Arguments" table of its docs page. Each agent's info holds
its own ``cell``, ``state``, ``position``, ``layer``, ``action_mask``, ``illegal_action`` and the
shared ``coverage``, ``new_cells``, ``steps``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import ParallelEnv

from bounce_gym.envs.drifters.base import DrifterEnvBase
from bounce_gym.envs.drifters.core import PER_DRIFTER, action_code
from bounce_gym.envs.parallel_step import check_parallel_actions, finish_parallel_step
from bounce_gym.validate import integer

#: arguments of `bounce_gym.envs.drifters.options.DrifterOptions` the fleet does not take (it covers the
#: surface; its clock runs to max_cycles)
SINGLE_ONLY = ("task", "goal", "region", "reward", "start", "clock_steps")


class MultiDrifterEnv(DrifterEnvBase, ParallelEnv):
    """The parallel form; see the module docstring."""

    metadata = {**DrifterEnvBase.metadata, "name": "multi_drifter_v0",
                "is_parallelizable": True}
    option_defaults = {"task": "cover"}
    not_taken = SINGLE_ONLY

    def __init__(self, max_cycles: int = 500, render_mode: str | None = None,
                 field_style: str = "arrows", **options: object) -> None:
        self.max_cycles = integer("max_cycles", max_cycles, 1)
        deploy = options.get("deploy")
        per_entry = {"n_drifters": len(deploy)} if isinstance(deploy, list | tuple) else {}
        self._build(options, render_mode, field_style, clock_steps=self.max_cycles,
                    start_key="deploy", defaults=per_entry)  # one drifter per deploy entry
        n = self.options.n_drifters
        self.possible_agents = [f"drifter_{k}" for k in range(n)]
        self.agent_index = {a: k for k, a in enumerate(self.possible_agents)}
        self._obs_space = spaces.Box(self.core.obs_low, self.core.obs_high, dtype=np.float32)
        self._action_space = spaces.Discrete(3)
        self.state_space = spaces.Box(0.0, 1.0, (3 * n,), dtype=np.float32)
        self.agents: list[str] = []
        self.np_random: np.random.Generator | None = None
        self.np_random_seed: int | None = None

    def observation_space(self, agent: str) -> spaces.Space:
        """The same (shared) space object on every call, as PettingZoo's API test requires."""
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_space

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None or self.np_random is None:
            self.np_random, self.np_random_seed = seeding.np_random(seed)
        obs, info = self.core.reset(self.np_random, options, strict=False)
        self.agents = list(self.possible_agents)
        self.cycles = 0
        if self.render_mode == "human":
            self.render()
        return self._per_agent(obs), self._agent_infos(info, self.agents)

    def step(self, actions: Mapping):
        check_parallel_actions(self, actions)
        codes = np.array([action_code(actions[a], f"action of {a}") for a in self.possible_agents])
        assert self.np_random is not None  # check_parallel_actions: reset() came first
        obs, rewards, terminated, info = self.core.step(codes, self.np_random)
        return finish_parallel_step(self, obs, rewards, terminated, info)

    def check_action(self, agent: str, action: object) -> int:
        """The action code of ``agent``; `ActionError` naming the agent and what is allowed for
        anything but 0, 1 or 2, and with ``illegal_action="error"`` for a move that is illegal
        now. The AEC form checks each action with it as it is given."""
        code = action_code(action, f"action of {agent}")
        k = self.agent_index[agent]
        if self.options.illegal_action == "error" and not self.core.is_legal(k, code):
            raise self.core.illegal(k, code, f"action of {agent}")
        return code

    def action_mask(self, agent: str) -> np.ndarray:
        """(3,) int8, the legal actions of ``agent`` now."""
        return self.core.legal()[self.agent_index[agent]].astype(np.int8)

    def state(self) -> np.ndarray:
        positions = self.core.fleet.positions()
        x, y = self.core.normalise(positions[:, 0], positions[:, 1])
        layer = self.core.fleet.layers() / max(self.core.model.n_layers - 1, 1)
        flat = np.column_stack((x, y, layer)).ravel().astype(np.float32)
        return np.clip(flat, 0.0, 1.0)

    def _per_agent(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        return {a: obs[self.agent_index[a]] for a in self.agents}

    def _agent_infos(self, info: dict, agents) -> dict[str, dict]:
        """Each agent's info: the shared entries and its own row of every per-drifter one."""
        shared = {k: v for k, v in info.items() if k not in PER_DRIFTER}
        rows = {k: info[k] for k in PER_DRIFTER if k in info}
        return {a: {**shared, **{k: v[self.agent_index[a]] for k, v in rows.items()}}
                for a in agents}
