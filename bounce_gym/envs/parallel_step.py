"""The checks and the end of a PettingZoo parallel step, shared by the bouncing and the drifter
fleets."""

from __future__ import annotations

from collections.abc import Mapping

from bounce_gym.errors import ActionError, ConfigError


def check_parallel_actions(env, actions) -> None:
    """``actions`` must map every live agent of ``env`` (and no other) to an action; a step
    before `reset` is a `ConfigError`."""
    if not getattr(env, "agents", None):
        raise ConfigError("step() called with no live agents: call reset() first")
    if not isinstance(actions, Mapping):
        raise ActionError(f"actions: expected a dict agent -> action, got "
                          f"{type(actions).__name__}")
    unknown = sorted(set(actions) - set(env.agents))
    missing = [a for a in env.agents if a not in actions]
    if unknown or missing:
        raise ActionError(f"actions: need exactly one action per live agent "
                          f"(unknown {unknown}, missing {missing})")


def finish_parallel_step(env, obs, rewards, terminated, info) -> tuple:
    """Count the cycle, split the core's per-robot arrays into per-agent dicts for the agents
    still live, drop the agents that are done, render in human mode; returns PettingZoo's
    ``(observations, rewards, terminations, truncations, infos)``.

    ``env`` has ``cycles``, ``max_cycles``, ``agents``, ``agent_index``, ``_per_agent(obs)``,
    ``_agent_infos(info, live)``, ``render_mode`` and ``render()``.
    """
    env.cycles += 1
    truncated = env.cycles >= env.max_cycles
    live = list(env.agents)
    result = (
        env._per_agent(obs),
        {a: float(rewards[env.agent_index[a]]) for a in live},
        {a: bool(terminated[env.agent_index[a]]) for a in live},
        dict.fromkeys(live, truncated),
        env._agent_infos(info, live),
    )
    env.agents = [a for a in live if not (result[2][a] or truncated)]
    if env.render_mode == "human":
        env.render()
    return result
