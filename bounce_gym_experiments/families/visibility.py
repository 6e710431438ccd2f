"""Safe bounce plans (Nilles et al., 2021): an experiment with a ``visibility`` block starts on
a boundary segment and either reaches a goal segment or patrols a limit cycle, with the safe plan
of `baselines.visibility.scenario.VisibilityScenario` as its planner.

Per episode: ``success`` (goal segment reached, or the last contact on the limit cycle). A goal
episode ends at the first contact on the goal segment. Plots: P' with segment ids, G_safe, and
the plan's cone of trajectories or the patrolled limit cycle.
"""

from __future__ import annotations

import numpy as np

from bounce_gym.envs.registration import is_pettingzoo_id
from bounce_gym_experiments.families.base import Episode, Family


class ScenarioEpisode(Episode):
    """Starts on the scenario's start segment; the scenario says when it is done and whether it
    succeeded."""

    def __init__(self, scenario) -> None:
        self.scenario = scenario

    def start_options(self, seed):
        return self.scenario.start_options(np.random.default_rng(seed))

    def step(self, info):
        return self.scenario.done(info)

    def metrics(self, info):
        return {"success": self.scenario.success(info)}


class Visibility(Family):
    name = "visibility"
    columns = (*Family.columns, "success")
    score = "success"
    takes_visibility = True

    def claims(self, experiment):
        return "visibility" in experiment and not is_pettingzoo_id(experiment["env"])

    def prepare(self, env, experiment):
        from baselines.visibility.scenario import VisibilityScenario

        return VisibilityScenario.for_experiment(env, experiment["visibility"])

    def planner(self, env, experiment, setup):
        return setup.planner(seed=0)

    def episode(self, env, policy, setup):
        return ScenarioEpisode(setup)

    def collect(self, data, env, policy, setup):
        data["scenario"] = setup

    def plots(self, folder, name, data):
        from bounce_gym_experiments.plots import visibility as vis

        scenario = data.get("scenario")
        if scenario is None:
            return []
        written = [
            vis.plot_partition(scenario.part, folder / f"{name}-partition.png",
                               title=f"{name}: P' with segment ids"),
            vis.plot_safe_graph(scenario.graph, folder / f"{name}-safe-graph.png",
                                title=f"{name}: safe graph"),
        ]
        if scenario.goal is None:
            written.append(vis.plot_limit_cycle(scenario.part, scenario.plan,
                                                folder / f"{name}-limit-cycle.png",
                                                title=f"{name}: patrolled limit cycle"))
        else:
            written.append(vis.plot_plan_cone(
                scenario.part, scenario.plan, folder / f"{name}-plan.png",
                title=f"{name}: {scenario.plan.kind} plan {scenario.start}→{scenario.goal}"))
        return written


FAMILY = Visibility()
