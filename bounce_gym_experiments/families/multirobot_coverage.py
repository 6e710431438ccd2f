"""Joint coverage by several robots: Alam, Bobadilla & Shell (2018) and Alam & Bobadilla
(Algorithm 1), the joint trajectory executed with turn commands for the neighbour jumps
(`baselines.multirobot.policies.CoveragePlanPolicy`).

Per episode, besides the team columns: ``steps_to_full`` — env steps until ``info["coverage"]``
first reaches 1 (every free cell at cell size = step length visited; a turn command counts as
one step), ``None`` if not within ``max_steps``; the episode stops there — the final
``coverage``, ``full`` (whether it was reached) and the score, ``steps_to_full_capped``: steps
to full coverage with an episode that never got there counted at the horizon (right-censored
at ``max_cycles``; ``full`` says how many were). The final coverage is no score: within the
benchmark's 500 steps every policy covers 98–99% of the cells. The planner also reports
``predicted_steps_to_full``. Plots: visit counts per cell, and steps to full coverage against
the number of robots.
"""

from __future__ import annotations

import numpy as np

from bounce_gym_experiments.families.multirobot import MultiRobot, TeamEpisode
from bounce_gym_experiments.plots.figures import pyplot, save_figure


class CoverageEpisode(TeamEpisode):
    """``start`` (seed → reset options, or ``None``): the start the experiment imposes on every
    policy."""

    def __init__(self, env, start=None) -> None:
        super().__init__(env)
        self.start_of = start
        self.steps_to_full = None
        self.horizon = int(self.inner.max_cycles)

    def start_options(self, seed):
        return None if self.start_of is None else self.start_of(seed)

    def start(self, info):
        if info["coverage"] >= 1.0:
            self.steps_to_full = 0
        return self.steps_to_full is not None

    def step(self, info):
        super().step(info)
        if info["coverage"] >= 1.0:
            self.steps_to_full = self.steps
        return self.steps_to_full is not None

    def metrics(self, info):
        capped = self.horizon if self.steps_to_full is None else self.steps_to_full
        return {**super().metrics(info), "full": self.steps_to_full is not None,
                "steps_to_full": self.steps_to_full, "steps_to_full_capped": capped,
                "coverage": float(info["coverage"])}


class MultiRobotCoverage(MultiRobot):
    name = "multirobot coverage"
    task = "coverage"
    table = "multi-robot coverage"
    columns = ("experiment", "policy", "robots", "episodes", "seeds", "steps_to_full_capped",
               "full", "steps_to_full", "predicted_steps_to_full", "coverage", "ticks",
               "robot_contacts")
    score = "steps_to_full_capped"
    higher_is_better = False
    planner_attributes = ("predicted_steps_to_full",)
    planner_class = "CoveragePlanPolicy"

    def prepare(self, env, experiment):
        """On a continuous backend the planner, built once per env: Algorithm 1 plans from a
        joint cell, so every policy starts where the planner's random joint cell puts the
        robots (`CoveragePlanPolicy.start_options`: cell centres and bin headings, drawn from
        the seed) — the same draw for all. On the cell backend the env's own draw is a joint
        cell: ``None`` (and where the angles are not discrete: no planner applies, and
        `MultiRobot.policies` says why)."""
        options = env.unwrapped.options
        if options.backend == "cell" or options.action_type != "discrete":
            return None
        return super().planner(env, experiment, None)

    def planner(self, env, experiment, setup):
        return super().planner(env, experiment, setup) if setup is None else setup

    def episode(self, env, policy, setup):
        if setup is None:
            return CoverageEpisode(env)
        return CoverageEpisode(env, lambda seed: setup.start_options(env, seed))

    def collect(self, data, env, policy, setup):
        super().collect(data, env, policy, setup)
        task = env.unwrapped.task
        data.setdefault("visits", {})[policy.name] = task.visits.copy()
        data["free"] = task.free

    def plots(self, folder, name, data):
        if not data.get("visits"):
            return []
        plt = pyplot()
        items = list(data["visits"].items())
        fig, axes = plt.subplots(1, len(items), figsize=(3.0 * len(items), 2.8), squeeze=False)
        for ax, (policy, visits) in zip(axes[0], items, strict=True):
            shown = np.where(data["free"], np.log1p(visits), np.nan)  # blocked cells blank
            ax.imshow(shown, origin="lower", cmap="magma")
            ax.set_title(f"{policy}: {np.count_nonzero(visits)} cells", fontsize=8)
            ax.axis("off")
        fig.suptitle(f"{name}: log(1 + ticks) per cell (first seed)", fontsize=9)
        return [save_figure(fig, folder / f"{name}-visits.png")]

    def summary_plots(self, folder, plots, summary):
        """Steps to full coverage (mean over the episodes that reached it, with its 95%
        interval) against the number of robots, one figure per (world, backend) with at least
        two team sizes."""
        by_world: dict[str, list[dict]] = {}
        for row in summary:
            data = plots.get(row["experiment"], {})
            if data.get("family") is self and row.get("steps_to_full") is not None:
                key = f"{data['world'].name}-{data['backend']}"
                by_world.setdefault(key, []).append(row)
        plt = pyplot()
        written = []
        for world, rows in by_world.items():
            if len({r["robots"] for r in rows}) < 2:
                continue
            fig, ax = plt.subplots(figsize=(4.2, 3.0))
            for policy in dict.fromkeys(r["policy"] for r in rows):
                mine = sorted((r for r in rows if r["policy"] == policy),
                              key=lambda r: r["robots"])
                values = np.array([r["steps_to_full"] for r in mine], dtype=float)
                bounds = np.array([[r.get("steps_to_full_lo"), r.get("steps_to_full_hi")]
                                   for r in mine], dtype=float)  # None (one episode) -> nan
                bounds = np.where(np.isnan(bounds), values[:, None], bounds)
                ax.errorbar([r["robots"] for r in mine], values,
                            yerr=[values - bounds[:, 0], bounds[:, 1] - values], marker="o",
                            capsize=3, label=policy)
            ax.set_xticks(sorted({r["robots"] for r in rows}))
            ax.set_xlabel("robots m")
            ax.set_ylabel("steps to full coverage")
            ax.set_title(f"{world}: mean over covered episodes, 95% CI", fontsize=9)
            ax.legend(fontsize=7)
            written.append(save_figure(fig, folder / f"steps-vs-robots-{world}.png"))
        return written


FAMILY = MultiRobotCoverage()
