"""Bad actions through the AEC and parallel forms of every multi-agent env are `ActionError`s
naming the agent and what is allowed, raised at the step that gives them (issue 22, item 10);
a done agent's None stays legal."""

import warnings

import numpy as np
import pettingzoo
import pytest
from pettingzoo.utils.conversions import aec_to_parallel

import bounce_gym  # noqa: F401  (registers the environments)
from bounce_gym.envs.drifters import multi_drifter_v0
from bounce_gym.envs.drifters.multi_env import MultiDrifterEnv
from bounce_gym.envs.multi_bounce_env import MultiBounceAEC
from bounce_gym.envs.patrol import patrol_v0
from bounce_gym.envs.patrol.env import PatrolEnv
from bounce_gym.errors import ActionError

IDS = ["bounce_gym/MultiBounce-v0", "bounce_gym/MultiBounceCoverage-v0",
       "bounce_gym/MultiBounceMonitoring-v0", "bounce_gym/MultiDrifter-v0",
       "bounce_gym/Patrol-v0"]
BAD = {"nan": np.nan, "string": "x", "None": None, "float": 1.5, "negative": -1, "too big": 99,
       "list": [0, 1], "bool": True, "array": np.array([0.5]), "object": object()}
#: what each env's message says is allowed
ALLOWED = {"robot": r"\[0, 3\)|expected an integer index",
           "drifter": r"expected 0 \(drift\), 1 \(up\) or 2 \(down\)",
           "patroller": r"expected an integer in \[0, 7\]"}


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _allowed(agent: str) -> str:
    return ALLOWED[agent.rsplit("_", 1)[0]]


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("action", BAD.values(), ids=BAD.keys())
def test_aec_refuses_a_bad_action_at_once_and_changes_nothing(env_id, action):
    env = pettingzoo.make("aec", env_id)
    env.reset(seed=0)
    agent = env.agent_selection
    with pytest.raises(ActionError, match=rf"^action of {agent}: .*({_allowed(agent)})"):
        env.step(action)
    assert env.agent_selection == agent
    env.step(0)  # the same agent may still act, and the episode goes on
    assert env.agents


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("action", BAD.values(), ids=BAD.keys())
def test_parallel_refuses_a_bad_action(env_id, action):
    env = pettingzoo.make("parallel", env_id)
    env.reset(seed=0)
    first = env.agents[0]
    with pytest.raises(ActionError, match=rf"^action of {first}: .*({_allowed(first)})"):
        env.step(dict.fromkeys(env.agents, action))


@pytest.mark.parametrize("make", [multi_drifter_v0.env, patrol_v0.env])
def test_the_first_agents_bad_action_is_refused_before_the_others_choose(make):
    """parallel_to_aec alone stored it and let the parallel step find it at the last agent."""
    env = make()
    env.reset(seed=0)
    first = env.agent_selection
    with pytest.raises(ActionError, match=f"action of {first}"):
        env.step("x")
    assert env.agent_selection == first


def test_an_illegal_move_is_refused_at_its_agents_aec_step():
    drifters = multi_drifter_v0.env(illegal_action="error", n_drifters=2)
    drifters.reset(seed=0)  # every drifter starts at the surface: up is illegal
    with pytest.raises(ActionError, match=r"action of drifter_0: up is illegal .*legal actions"):
        drifters.step(1)
    patrol = patrol_v0.env(illegal_action="error", start=[0, 5])
    patrol.reset(seed=0)
    mask = patrol.unwrapped.action_mask("patroller_0")
    illegal = int(np.flatnonzero(mask == 0)[0])
    with pytest.raises(ActionError, match=r"action of patroller_0: .* is illegal at vertex 0"):
        patrol.step(illegal)
    patrol.step(int(np.flatnonzero(mask)[0]))
    assert patrol.agent_selection == "patroller_1"


def _run_to_a_done_agent(env) -> str:
    env.reset(seed=0)
    for agent in env.agent_iter():
        if env.terminations[agent] or env.truncations[agent]:
            return agent
        env.step(0)
    raise AssertionError("no agent finished")


@pytest.mark.parametrize("make", [
    lambda: pettingzoo.make("aec", "bounce_gym/MultiBounce-v0", n_robots=2, max_cycles=3),
    lambda: multi_drifter_v0.env(n_drifters=2, max_cycles=3),
    lambda: patrol_v0.env(max_cycles=22, attack_time=20),
])
def test_a_done_agent_takes_none_and_nothing_else(make):
    env = make()
    agent = _run_to_a_done_agent(env)
    with pytest.raises(ActionError, match=rf"action of {agent}: the agent is done .* the only "
                                          r"allowed action is None, got 0"):
        env.step(0)
    env.step(None)
    assert agent not in env.agents


def test_aec_to_parallel_still_gives_the_parallel_env_back():
    assert isinstance(aec_to_parallel(multi_drifter_v0.env()), MultiDrifterEnv)
    assert isinstance(aec_to_parallel(patrol_v0.env()), PatrolEnv)
    assert isinstance(pettingzoo.make("aec", "bounce_gym/MultiBounce-v0").unwrapped,
                      MultiBounceAEC)
