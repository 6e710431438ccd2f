"""Draw the patrolling figures: the distributed visibility policies' chains on ``patrol_15x15``
(thesis Fig. 4.9) and p_d(t_a) of the distributed and centralised policies (Tables 4.6/4.7,
Figs 4.15/4.17) (Alam 2018, thesis ch. 4).

Also a frame of ``bounce_gym/Patrol-v0`` in the middle of an attack (MAECT patrollers against
the best-responding adversary), as the env renders it.

Run from the repository root: ``.venv/bin/python docs/make_patrol_figures.py`` (writes
``docs/patrol_policies.png``, ``docs/patrol_pd.png`` and ``docs/patrol_episode.png``; a few
minutes, most of it the three centralised chains on the 253-vertex graph).
"""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pettingzoo  # noqa: E402
from PIL import Image  # noqa: E402

import bounce_gym  # noqa: E402, F401  (registers Patrol-v0)
from baselines.patrolling import (  # noqa: E402
    cell_graph,
    centralised_chains,
    centralised_plan,
    centralised_starts,
    distributed_chains,
    remote_target,
    solve_maect,
)
from baselines.patrolling.policies import (  # noqa: E402
    BestResponseAdversary,
    JointPatrolPolicy,
    MarkovPatrolPolicy,
)
from baselines.patrolling.visibility import cell_visibility, watch_region  # noqa: E402
from baselines.patrolling.vulnerability import detection_curve, detection_times  # noqa: E402
from bounce_gym.files import atomic_write  # noqa: E402
from bounce_gym.worlds import get  # noqa: E402

HERE = Path(__file__).parent
RANGE, RUNS, TOL = 6.0, 5000, 1e-6
#: thesis Tables 4.6 and 4.7
T_A = [20, 30, 40, 50, 100, 500]
THESIS = {"distributed": [0.5139118, 0.642008, 0.726392, 0.7844395, 0.9109307, 0.9926246],
          "centralised": [0.1902747, 0.2696536, 0.3383983, 0.3988624, 0.6166325, 0.9656368]}


def _save(figure, name: str) -> Path:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=90)
    plt.close(figure)
    path = HERE / name
    atomic_write(path, buffer.getvalue())
    return path


def _setting(name: str):
    world = get(name)
    return world, cell_graph(world), cell_visibility(world.occupancy(1.0), RANGE)


def _draw_map(ax, world, vis) -> None:
    free = world.occupancy(1.0)
    ax.imshow(~free, origin="lower", cmap="Greys", vmin=0, vmax=1.6,
              extent=(0, free.shape[1], 0, free.shape[0]))
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def policies_figure(world, graph, vis, chains, target) -> Path:
    figure, axes = plt.subplots(1, len(chains), figsize=(5 * len(chains), 5.2))
    centre = vis.cells[:, ::-1] + 0.5
    for i, (ax, chain) in enumerate(zip(axes, chains, strict=True)):
        _draw_map(ax, world, vis)
        weights = chain.result.weights
        top = max(weights.values())
        for (u, v), w in weights.items():
            ax.plot(*centre[[u, v]].T, color="tab:blue", lw=0.3 + 4.5 * w / top,
                    solid_capstyle="round")
        ax.scatter(*centre[list(chain.subset)].T, s=60, color="tab:orange", edgecolor="k",
                   zorder=3, label=f"cover centres Q_{i + 1} ({len(chain.subset)})")
        ax.scatter(*centre[target], s=160, marker="*", color="tab:red", edgecolor="k", zorder=4,
                   label="target (Tables 4.6)")
        ax.set_title(f"robot {i + 1}: problem 4.5, line width ∝ edge weight")
        ax.legend(loc="lower left", fontsize=8)
    figure.suptitle("Distributed visibility policies on patrol_15x15 (188 cells, l = 6)")
    figure.tight_layout()
    return _save(figure, "patrol_policies.png")


def _times(case: str):
    if case == "distributed":
        world, graph, vis = _setting("patrol_15x15")
        chains = distributed_chains(graph, vis, 2, tol=TOL)
        watch = watch_region(vis, remote_target(graph, chains))
        starts, per_robot = watch.outside, False
    else:
        world, graph, vis = _setting("patrol_18x16")
        plan = centralised_plan(graph, vis, vis, 3)
        chains = centralised_chains(graph, plan, tol=TOL)
        watch = watch_region(vis, remote_target(graph, chains))
        starts, per_robot = centralised_starts(plan, watch), True
    times = detection_times([c.transition for c in chains], watch.boundary, starts=starts,
                            per_robot_starts=per_robot, n_runs=RUNS, seed=0)
    return (world, graph, vis, chains, watch.target), times


def pd_figure(times: dict) -> Path:
    figure, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    t = np.arange(0, 501)
    for ax, (case, sample) in zip(axes, times.items(), strict=True):
        curve = detection_curve(sample, t)
        whole = detection_curve(sample, np.arange(int(sample.max()) + 1), gld=curve.gld)
        ks = np.abs(whole.fitted - whole.empirical).max()
        ax.step(t, curve.empirical, where="post", color="k", lw=1, label="empirical CDF")
        ax.plot(t, curve.fitted, color="tab:blue", lw=2, label=f"fitted GλD (KS {ks:.3f})")
        ax.plot(T_A, THESIS[case], "o", color="tab:red", label="thesis table")
        ax.set_xscale("symlog", linthresh=10)
        ax.set_xlabel("t_a (steps)")
        table = "4.6" if case == "distributed" else "4.7"
        ax.set_title(f"{case} (Table {table}), n_o = {len(sample)}")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize=8)
    axes[0].set_ylabel("p_d(t_a) = Pr[T ≤ t_a]")
    figure.tight_layout()
    return _save(figure, "patrol_pd.png")


def episode_figure(seed: int = 10_000, steps: int = 8) -> Path:
    """A rendered frame of Patrol-v0 on patrol_15x15 ``steps`` steps into episode ``seed``: two
    MAECT patrollers with their sensor regions, the best response's attack and its progress."""
    maect = solve_maect(cell_graph(get("patrol_15x15")))
    env = pettingzoo.make("parallel", "bounce_gym/Patrol-v0", strategy=maect.transition,
                          render_mode="rgb_array")
    policy = JointPatrolPolicy(MarkovPatrolPolicy([maect.transition]), BestResponseAdversary())
    observations, infos = env.reset(seed=seed, options=policy.start_options(env, seed))
    policy.reset(env)
    for _ in range(steps):
        observations, _, _, _, infos = env.step(policy.act(observations, infos))
    buffer = io.BytesIO()
    Image.fromarray(env.render()).resize((400, 400), Image.LANCZOS).save(buffer, format="png")
    env.close()
    path = HERE / "patrol_episode.png"
    atomic_write(path, buffer.getvalue())
    return path


if __name__ == "__main__":
    distributed, distributed_sample = _times("distributed")
    written = [episode_figure(), policies_figure(*distributed)]
    _, centralised_sample = _times("centralised")
    written.append(pd_figure({"distributed": distributed_sample,
                              "centralised": centralised_sample}))
    for path in written:
        print(f"{path.name}: {path.stat().st_size // 1024} KiB")
