"""Multi-robot experiments of `experiments.evaluation`: PettingZoo parallel envs, shared policies.

An experiment whose ``env`` is a PettingZoo id (``bounce_gym/MultiBounce-v0``,
``bounce_gym/MultiBounceCoverage-v0``, ``bounce_gym/MultiBounceMonitoring-v0``) runs here. The
env is built with ``pettingzoo.make("parallel", env, max_cycles=max_steps, **env_kwargs)``, so
``max_steps`` is also the env's episode length (``env_kwargs`` may not set ``max_cycles``).
Extra experiment keys:

* ``planner_kwargs`` — keyword arguments of the planner's ``for_env`` (e.g. ``{phi: 135}``);
* ``rl_models`` — the sub-folder of ``models/`` holding the shared-policy models (default: the
  experiment name), so several experiments (say m = 2..5) can use one trained model.

Policies (`baselines.policy.MultiPolicy`):

* ``planner`` — coverage: `baselines.multirobot.policies.CoveragePlanPolicy` (Algorithm 1's
  joint trajectory, executed with turn commands for the neighbour jumps); monitoring:
  `baselines.multirobot.policies.MonitoringPlanPolicy` (Algorithm 2: the robots start on an
  accepted collision-free periodic group);
* ``random`` — random bouncing: every robot a uniformly random angle of its Φ_i at every step
  (never a turn command);
* ``fixed`` — every robot always the same angle, one policy per angle of robot 0's Φ;
* ``rl`` — every PPO model ``models/<rl_models>/*.zip`` (``train.py`` with a PettingZoo id saves
  them) as ONE policy shared by all robots: each live robot's action is drawn from the model's
  action distribution for its own observation (`SharedSB3Policy`).

Per episode (one row per experiment, policy, seed), besides steps, ticks and the team return
(rewards summed over robots and steps): ``robots`` (m) and ``robot_contacts`` (robots that ended
a step blocked by another robot, summed over steps: a head-on pair counts twice), and

* coverage: ``steps_to_full`` — env steps until ``info["coverage"]`` first reaches 1 (every free
  cell at cell size = step length visited; a turn command counts as one step), ``None`` if not
  within ``max_steps``; the episode stops there — and the final ``coverage``; the planner also
  reports ``predicted_steps_to_full`` (Algorithm 1 on the joint cell model);
* monitoring: ``in_region`` (``info["in_region_fraction"]`` averaged over robots and steps) and
  ``encounters`` (robot pairs together at the end of a step, summed); the planner also reports
  ``r`` (accepted periodic groups) and ``period`` (of the group it runs).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import pettingzoo

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.policy import MultiPolicy
from bounce_gym.envs.registration import PETTINGZOO_ENVS
from bounce_gym.errors import ConfigError

MULTI_ENV_IDS = tuple(PETTINGZOO_ENVS)


def is_multi(env_id: str) -> bool:
    """Whether an experiment's env id is one of the multi-robot (PettingZoo) ids."""
    return env_id in MULTI_ENV_IDS


def validate_multi_experiment(where: str, exp: dict) -> None:
    """The checks specific to a multi-robot experiment (``exp`` has its defaults already)."""
    if "visibility" in exp:
        raise ConfigError(f"{where}.visibility: only for single-robot experiments")
    if "max_cycles" in exp["env_kwargs"]:
        raise ConfigError(f"{where}.env_kwargs.max_cycles: not allowed; the experiment's "
                          "max_steps is the env's max_cycles")
    exp.setdefault("planner_kwargs", {})


def make_multi_env(exp: Mapping):
    """The experiment's parallel env, with ``max_cycles = max_steps``."""
    return pettingzoo.make("parallel", exp["env"], max_cycles=exp["max_steps"],
                           **exp["env_kwargs"])


# -- simple policies ---------------------------------------------------------------------------

class RandomBouncePolicy(MultiPolicy):
    """Random bouncing: each live robot a uniformly random index of its own Φ_i every step (turn
    commands, indices past Φ_i, are never chosen). The random stream restarts from the episode's
    seed, so an episode does not depend on the ones run before it."""

    name = "random"

    def start_options(self, env, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        return None

    def reset(self, env) -> None:
        inner = env.unwrapped
        self.n = {a: len(inner.options.angles[i]) for a, i in inner.agent_index.items()}

    def act(self, observations, infos):
        return {a: int(self.rng.integers(self.n[a])) for a in observations}


class FixedBouncePolicy(MultiPolicy):
    """Every robot always bounces with angle ``index`` of its Φ_i (the papers' φ for all)."""

    def __init__(self, index: int, degrees: float) -> None:
        self.index = int(index)
        self.name = f"fixed {degrees:g}°"

    def act(self, observations, infos):
        return dict.fromkeys(observations, self.index)


class SharedSB3Policy(MultiPolicy):
    """A Stable-Baselines3 PPO model as one policy shared by every robot (parameter sharing, as
    in training through `baselines.rl.parallel_vec_env.ParallelToVecEnv`).

    Every step the model gives each live robot's action distribution from its own observation
    (one batched forward pass), and each robot's action is **sampled** from it with a generator
    seeded by the episode's seed — the stochastic policy PPO trained. Its greedy (argmax) version
    is a poor baseline here: robots that sense only contact and clock and share one deterministic
    policy act alike and lock into cycles (grid_10x10, m = 2: 52 % coverage in 5000 steps where
    the sampled policy covers everything).
    """

    def __init__(self, path: Path) -> None:
        from stable_baselines3 import PPO

        if not path.stem.lower().startswith("ppo"):
            raise ConfigError(f"model {path}: a multi-robot shared policy must be a PPO model "
                              "(file name ppo_*.zip, as train.py saves it)")
        self.model = PPO.load(path, device="cpu")
        self.path = path
        self.name = f"rl {path.stem}"

    def start_options(self, env, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        return None

    def reset(self, env) -> None:
        agent = env.possible_agents[0]
        obs_space, act_space = env.observation_space(agent), env.action_space(agent)
        if self.model.observation_space != obs_space or self.model.action_space != act_space:
            raise ConfigError(
                f"rl_models: {self.path} was trained for observations "
                f"{self.model.observation_space} and actions {self.model.action_space}, but this "
                f"experiment's robots have {obs_space} and {act_space} (train with the same "
                "env_kwargs)")

    def act(self, observations, infos):
        import torch

        live = list(observations)
        batch, _ = self.model.policy.obs_to_tensor(np.stack([observations[a] for a in live]))
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # a batch of m tiny rows: intra-op threads only add overhead
        try:
            with torch.no_grad():
                probs = self.model.policy.get_distribution(batch).distribution.probs.numpy()
        finally:
            torch.set_num_threads(threads)
        cumulative = np.cumsum(probs, axis=1)
        draws = self.rng.random((len(live), 1)) * cumulative[:, -1:]
        actions = np.minimum((cumulative <= draws).sum(axis=1), probs.shape[1] - 1)
        return {a: int(act) for a, act in zip(live, actions, strict=True)}


def shared_rl_policies(folder: Path) -> list[MultiPolicy]:
    """One `SharedSB3Policy` per model file in ``folder`` (none if it does not exist)."""
    return [SharedSB3Policy(p) for p in sorted(folder.glob("*.zip"))] if folder.is_dir() else []


# -- planners ----------------------------------------------------------------------------------

def _coverage_planner(env, kwargs: Mapping) -> MultiPolicy:
    from baselines.multirobot.policies import CoveragePlanPolicy

    return CoveragePlanPolicy.for_env(env, **kwargs)


def _monitoring_planner(env, kwargs: Mapping) -> MultiPolicy:
    from baselines.multirobot.policies import MonitoringPlanPolicy

    return MonitoringPlanPolicy.for_env(env, **kwargs)


PLANNERS: dict[str, Callable] = {"coverage": _coverage_planner, "monitoring": _monitoring_planner}


def multi_policies_for(exp: Mapping, env, models_dir: Path) -> list[MultiPolicy]:
    """The experiment's policies, built once and run on every seed."""
    inner = env.unwrapped
    task = inner.core.task.name
    if inner.options.action_type != "discrete":
        raise ConfigError("env_kwargs.action_type: multi-robot experiments choose angles by index; "
                          "use 'discrete'")
    out: list[MultiPolicy] = []
    for kind in exp["policies"]:
        if kind == "planner":
            if task not in PLANNERS:
                raise ConfigError(f"policies: no multi-robot planner for task {task!r}; "
                                  f"planners exist for {sorted(PLANNERS)}")
            try:
                out.append(PLANNERS[task](env, exp["planner_kwargs"]))
            except TypeError as exc:
                raise ConfigError(f"planner_kwargs: {exc}") from None
        elif kind == "random":
            out.append(RandomBouncePolicy())
        elif kind == "fixed":
            n = min(len(phi) for phi in inner.options.angles)
            out += [FixedBouncePolicy(i, float(np.degrees(inner.options.angles[0][i])))
                    for i in range(n)]
        elif kind == "rl":
            out += shared_rl_policies(models_dir / exp.get("rl_models", exp["name"]))
    return out


# -- episodes ----------------------------------------------------------------------------------

def run_multi_episode(env, policy: MultiPolicy, seed: int, max_steps: int,
                      record: bool = False) -> tuple[dict, np.ndarray | None]:
    """One episode (the `MultiPolicy` call order); returns the metrics and, with ``record``, the
    positions (steps + 1, m, 2) of every robot.

    A coverage episode stops at the first step with full coverage."""
    inner = env.unwrapped
    task = inner.core.task.name
    options = policy.start_options(env, seed)
    obs, infos = env.reset(seed=seed, options=options)
    policy.reset(env)
    path = [inner.core.state.position.copy()] if record else None
    info = infos[inner.possible_agents[0]]
    steps, total, contacts, encounters, in_region = 0, 0.0, 0, 0, 0.0
    steps_to_full = 0 if task == "coverage" and info["coverage"] >= 1.0 else None
    while env.agents and steps < max_steps and steps_to_full is None:
        obs, rewards, _, _, infos = env.step(policy.act(obs, infos))
        steps += 1
        total += float(sum(rewards.values()))
        state = inner.core.state
        contacts += int(np.sum(state.blocked & (state.contact_robot >= 0)))
        info = next(iter(infos.values()))
        if task == "coverage" and info["coverage"] >= 1.0:
            steps_to_full = steps
        if task == "monitoring":
            in_region += float(np.mean(info["in_region_fraction"]))
            encounters += int(info["encounters"])
        if record:
            path.append(state.position.copy())
    metrics: dict = {"robots": inner.options.n_robots, "robot_contacts": contacts}
    if task == "coverage":
        metrics.update(steps_to_full=steps_to_full, coverage=float(info["coverage"]))
    elif task == "monitoring":
        metrics.update(in_region=in_region / max(steps, 1), encounters=encounters)
    for key in ("predicted_steps_to_full", "r", "period"):
        if getattr(policy, key, None) is not None:
            metrics[key] = getattr(policy, key)
    summary = {"steps": steps, "ticks": int(inner.core.state.ticks), "return": total,
               "metrics": metrics}
    return summary, None if path is None else np.array(path)


def run_multi_experiment(exp: Mapping, models_dir: Path, on_seed: Callable[[], None]
                         ) -> tuple[list[tuple[str, int, dict]], dict]:
    """Every policy on every seed of a validated multi-robot experiment.

    Returns ``(policy name, seed, episode summary)`` per episode and the plot data (world, task,
    each policy's first-seed paths (steps + 1, m, 2), coverage visit counts with the free-cell
    mask, or monitoring regions). ``on_seed`` is called after each seed (a progress bar)."""
    env = make_multi_env(exp)
    inner = env.unwrapped
    task = inner.core.task
    policies = multi_policies_for(exp, env, models_dir)
    episodes = []
    plot = {"world": inner.options.world, "backend": inner.options.backend, "task": task.name,
            "multi": True, "paths": {}, "visits": {}}
    for k, seed in enumerate(exp["seeds"]):
        for policy in policies:
            summary, path = run_multi_episode(env, policy, seed, exp["max_steps"], record=k == 0)
            episodes.append((policy.name, seed, summary))
            if k == 0:
                plot["paths"][policy.name] = path
                plot["regions"] = task.render_layers().get("regions")
                if task.name == "coverage":
                    plot["visits"][policy.name] = task.visits.copy()
                    plot["free"] = task.free
        on_seed()
    env.close()
    return episodes, plot
