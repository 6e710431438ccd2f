"""AEC forms that refuse a bad action with `ActionError` at the step that gives it.

PettingZoo's ``parallel_to_aec`` stores each agent's action unchecked and hands them to the
parallel env only once every agent has chosen, so a bad action of the first agent surfaced at
the last agent's step; its ``AssertOutOfBoundsWrapper`` answers with a bare ``AssertionError``.
Here each action is checked when it is given: an agent that is done (terminated or truncated)
may only pass None (PettingZoo's dead step); a live agent's action goes through the env's own
check, which names the agent and what is allowed.
"""

from __future__ import annotations

from pettingzoo.utils.conversions import parallel_to_aec_wrapper
from pettingzoo.utils.wrappers import OrderEnforcingWrapper

from bounce_gym.errors import ActionError


def check_dead_action(agent: str, action: object) -> None:
    """A done agent is stepped once with None before it leaves; anything else is refused."""
    if action is not None:
        raise ActionError(f"action of {agent}: the agent is done (terminated or truncated); the "
                          f"only allowed action is None, got {action!r}")


class _CheckedParallelToAEC(parallel_to_aec_wrapper):
    """``parallel_to_aec_wrapper`` that checks each action with ``env.check_action(agent,
    action)`` before storing it (still a ``parallel_to_aec_wrapper``, so PettingZoo's
    ``aec_to_parallel`` gives the parallel env back)."""

    def step(self, action) -> None:
        agent = self.agent_selection
        if self.terminations[agent] or self.truncations[agent]:
            check_dead_action(agent, action)
        else:
            self.env.check_action(agent, action)
        super().step(action)


def checked_parallel_to_aec(par_env) -> OrderEnforcingWrapper:
    """PettingZoo's ``parallel_to_aec(par_env)`` with every action checked as it is given;
    ``par_env`` has ``check_action(agent, action)`` raising `ActionError`."""
    return OrderEnforcingWrapper(_CheckedParallelToAEC(par_env))
