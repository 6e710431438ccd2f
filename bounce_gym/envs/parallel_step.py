"""The end of a PettingZoo parallel step, shared by the bouncing and the drifter fleets."""

from __future__ import annotations


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
