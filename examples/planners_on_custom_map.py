"""The analytic planners as a library, on a map of your own.

An L-shaped room with a square pillar is built as a `bounce_gym.worlds.World` from its
polygon, written to a YAML map file in ``--out`` and read back, as a map from elsewhere would be.
Two planners then work on it, each printing its plan and its prediction next to what was
measured:

* navigation (Alam, Bobadilla & Shell 2017, Sec. IV): `baselines.navigation.NavigationPlanner`
  plans on the roadmap over (cell, bounce angle) of ``BounceNavigation-v0``'s cell model and
  replays the plan by counting ticks, on held-out episode seeds (from 10,000). Printed: the
  feasible fraction, success on the feasible episodes (95 % Wilson intervals), and how often
  the papers' cost up to the goal (``info["plan_cost"]``) equals the plan's weight;
* safe bounce plans (Nilles et al., IJRR 2021, Sec. 7): the boundary partition, the graph of
  safe actions and the plan with the fewest bounces between two boundary segments, then its
  Monte-Carlo success from random start points and angles inside the plan's intervals, which
  a safe plan predicts to be 1.

Run with ``python examples/planners_on_custom_map.py`` (``--episodes``, ``--samples``,
``--out FOLDER``; the map is ``FOLDER/l_room.yaml``, by default in a fresh temporary folder
that is printed at the end).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import gymnasium as gym

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.navigation.policy import NavigationPlanner
from baselines.seeds import EVALUATION_SEEDS_START
from baselines.visibility.graph import safe_graph
from baselines.visibility.partition import partition
from baselines.visibility.planning import fewest_bounce_plan, monte_carlo
from bounce_gym import worlds
from bounce_gym.worlds import World
from bounce_gym_experiments.stats import wilson_interval

#: an L-shaped room (12 x 10 with the north-east quarter cut away) and a 2 x 2 pillar
OUTER = [(0, 0), (12, 0), (12, 5), (6, 5), (6, 10), (0, 10)]
PILLAR = [(2, 2), (4, 2), (4, 4), (2, 4)]


def write_map(folder: Path) -> Path:
    """The room as a YAML map file in ``folder``."""
    room = World(OUTER, [PILLAR], name="l_room")
    return worlds.save(room, folder / "l_room.yaml", description="an L-shaped room, one pillar")


def interval(successes: int, n: int) -> str:
    """``rate [low, high] n=N`` with the Wilson interval."""
    if n == 0:
        return "n=0"
    low, high = wilson_interval(successes, n)
    return f"{successes / n:.3f} [{low:.3f}, {high:.3f}] n={n}"


def navigation(path: Path, episodes: int) -> None:
    """Run the roadmap planner on ``episodes`` held-out episodes of the map at ``path``."""
    env = gym.make("bounce_gym/BounceNavigation-v0", world=str(path), backend="cell")
    planner = NavigationPlanner()
    feasible = reached = exact = 0
    for seed in range(EVALUATION_SEEDS_START, EVALUATION_SEEDS_START + episodes):
        obs, info = env.reset(seed=seed)
        planner.reset(env)
        plan = planner.plan
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(planner.act(obs, info))
            done = terminated or truncated
        if plan is None:
            continue
        feasible += 1
        reached += bool(info["is_success"])
        exact += info["plan_cost"] == planner.predicted_weight
        if feasible == 1:
            print(f"seed {seed}: plan '{plan}' (0 = a tick forward, n = a bump turning n°): "
                  f"predicted {planner.predicted_ticks} ticks, cost {planner.predicted_weight:g}; "
                  f"measured cost {info['plan_cost']:g}, goal reached {info['is_success']}, episode "
                  f"{info['ticks']} ticks (its last step drives on to the next bump)")
    env.close()
    print(f"navigation: feasible {interval(feasible, episodes)}; success on feasible "
          f"{interval(reached, feasible)}; measured cost = planned cost {interval(exact, feasible)}")


def safe_plan(room: World, samples: int) -> None:
    """The fewest-bounce safe plan from segment 0 to the farthest segment that has one."""
    part = partition(room)
    graph = safe_graph(part)
    print(f"bounce visibility: {len(part.start)} boundary segments, "
          f"{graph.number_of_edges()} safe arcs")
    plans = [p for goal in range(1, len(part.start))
             if (p := fewest_bounce_plan(graph, 0, goal)) is not None]
    if not plans:
        print("no safe plan leaves segment 0")
        return
    plan = max(plans, key=lambda p: len(p.path))
    rate, hits = monte_carlo(room, part, plan, n=samples, seed=0, return_counts=True)
    print(f"safe plan {plan.path}, angle intervals (rad) "
          f"{[(round(lo, 3), round(hi, 3)) for lo, hi in plan.intervals]}: predicted success 1; "
          f"measured {interval(hits, samples)} random starts and angles")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200, help="held-out navigation episodes")
    parser.add_argument("--samples", type=int, default=1000, help="Monte-Carlo runs of the plan")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the map file (default: a fresh temporary folder)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="custom_map_"))
    out.mkdir(parents=True, exist_ok=True)

    path = write_map(out)
    room = worlds.load(path)  # the map as any map file is read
    print(f"map {room.name} from {path}")
    navigation(path, args.episodes)
    safe_plan(room, args.samples)
    print(f"map file written to {path}")


if __name__ == "__main__":
    main()
