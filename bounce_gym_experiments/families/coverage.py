"""Coverage: spend time in every cell as the target distribution asks; the optimal mixture α of
bounce policies (`baselines.coverage.MixturePolicy`).

Per episode: ``coverage``, ``distance`` and ``tv_distance`` to the target. Plots: time per cell
against the target, and the planner's α.
"""

from __future__ import annotations

import math

import numpy as np

from bounce_gym_experiments.families.base import SingleRobotFamily
from bounce_gym_experiments.plots.figures import pyplot, save_figure


class Coverage(SingleRobotFamily):
    name = task = "coverage"
    columns = (*SingleRobotFamily.columns, "coverage", "distance")
    score = "distance"
    higher_is_better = False

    def make_planner(self, env):
        from baselines.coverage import MixturePolicy

        return MixturePolicy.for_env(env)

    def metrics(self, info):
        return {"coverage": info["coverage"], "distance": info["distance"],
                "tv_distance": info["tv_distance"]}

    def collect(self, data, env, policy, setup):
        task = env.unwrapped.task
        data.setdefault("visits", {})[policy.name] = task.visits.copy()
        data["target"] = task.target
        if hasattr(policy, "alpha"):
            data["alpha"] = (policy.alpha, [math.degrees(a) for a in
                                            env.unwrapped.options.angles[0]])

    def plots(self, folder, name, data):
        plt = pyplot()
        written = []
        if data.get("visits"):
            items = [("target", data["target"])] + [
                (p, v / max(v.sum(), 1e-12)) for p, v in data["visits"].items()]
            fig, axes = plt.subplots(1, len(items), figsize=(3.0 * len(items), 2.8),
                                     squeeze=False)
            # a shared scale, capped so that one concentrated policy does not blacken the rest
            top = 4 * float(np.max(data["target"]))
            for ax, (label, values) in zip(axes[0], items, strict=True):
                ax.imshow(values, origin="lower", vmin=0, vmax=top, cmap="magma")
                ax.set_title(label, fontsize=8)
                ax.axis("off")
            fig.suptitle(f"{name}: time spent per cell vs target (first seed)", fontsize=9)
            written.append(save_figure(fig, folder / f"{name}-coverage.png"))
        if "alpha" in data:
            alpha, degrees = data["alpha"]
            fig, ax = plt.subplots(figsize=(3.5, 2.5))
            ax.bar([f"{d:g}°" for d in degrees], alpha, color="#2a6fdb")
            ax.set_ylabel("α (share of time)")
            ax.set_title(f"{name}: optimal policy mixture", fontsize=9)
            written.append(save_figure(fig, folder / f"{name}-alpha.png"))
        return written


FAMILY = Coverage()
