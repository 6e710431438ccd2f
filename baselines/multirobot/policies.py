"""The multi-robot planners of Alam & Bobadilla as policies for `MultiBounceEnv` (2020, §4).

* `CoveragePlanPolicy` — executes the joint trajectory x̃ of Algorithm 1 (MULTIROBOTCOVERAGE,
  `baselines.multirobot.plan_coverage`): on a joint-map edge every robot bounces with its φ_i; on a
  neighbour jump (one robot's heading ±Δθ; docs/choices/multirobot.md, "A neighbour jump is a timed turn") the
  robot gets a clock-timed *turn command* and the others wait one tick (the env's ``turn_angles``).
  After the plan the robots keep bouncing with φ_i. Edges a turn cannot execute — a random restart,
  or a position jump of the ``"full"`` neighbourhood — end the plan there (``executable_steps``);
  the robots bounce on.
* `MonitoringPlanPolicy` — Algorithm 2 (PERSISTENTBEHAVIOR, `baselines.multirobot.monitoring`): lets the two
  robots bounce with their φ_i forever. With ``start="cycle"`` it first places them on an
  accepted collision-free joint limit cycle (`cycle_start`, chosen by the seed); the cycle then
  repeats with no robot–robot contact and visits each robot's region every period. With
  ``start="draw"`` (default) they start where the env draws them, as every other policy does.

Both are exact on the ``cell`` backend (the papers' grid model) in ``step_mode="tick"``: the env's
joint cell after step t is the plan's (tests replay whole plans). On the continuous backends they
run open loop from the grid plan — one tick is then ``step_length`` of driving, a diagonal king
move is √2 on the grid (docs/choices/multirobot.md, "Diagonal moves and the corner rule"), so the motion drifts
from the plan; `evaluate.py` reports how much coverage and how many contacts that costs.
"""

from __future__ import annotations

import math

import numpy as np

from baselines.multirobot.coverage import CoverageResult, plan_coverage, random_start
from baselines.multirobot.monitoring import MonitoringResult, joint_monitoring_cycles
from baselines.policy import START_OBSERVED, MultiPolicy
from bounce_gym.cells import CellModel, JointCellModel
from bounce_gym.errors import ConfigError

__all__ = ["MONITORING_STARTS", "CoveragePlanPolicy", "MonitoringPlanPolicy", "cycle_start",
           "regions_of"]

#: where `MonitoringPlanPolicy` starts the robots: ``draw`` (the env's random draw for the seed;
#: the default) or ``cycle`` (on an accepted cycle of Algorithm 2, `cycle_start`)
MONITORING_STARTS = ("draw", "cycle")


def _angle_index(env, robot: int, phi_deg: float) -> int:
    """The action index of φ in robot ``robot``'s angle set Φ_i."""
    angles = np.degrees(env.options.angles[robot])
    hit = np.flatnonzero(np.isclose(np.mod(angles - phi_deg + 180.0, 360.0) - 180.0, 0.0,
                                    atol=1e-6))
    if len(hit) == 0:
        raise ConfigError(f"phi: {phi_deg:g}° is not among robot_{robot}'s angles "
                          f"{angles.tolist()}; add it to the env's angles")
    return int(hit[0])


def _check_tick_mode(env, who: str) -> None:
    if env.options.step_mode != "tick":
        raise ConfigError(f"{who}: the plan is a sequence of ticks; make the env with "
                          "step_mode='tick'")


class CoveragePlanPolicy(MultiPolicy):
    """Execute Algorithm 1's joint trajectory (module docstring).

    Args:
        joint_model: the joint cell model the plan is made on (its angles are the φ_i).
        phi_index: per robot, the action index of its φ_i in the env's Φ_i.
        turn_index: ``{signed bins: action index offset}`` of the env's turn commands.
        neighbors: passed to `plan_coverage`.
        max_steps: passed to `plan_coverage`.
        lookahead: passed to `plan_coverage`.

    `start_options` draws the random start on continuous backends from its ``seed``; the
    planner's random fallback uses seed 0. After `reset`: ``result`` (the `CoverageResult`), ``predicted_steps_to_full`` (env steps
    until the plan covers every reachable free cell, or None) and ``executable_steps``.
    """

    name = "planner"
    #: the plan is made from the true joint start configuration, read at `reset`
    information = START_OBSERVED

    def __init__(self, joint_model: JointCellModel, phi_index: list[int],
                 turn_index: dict[int, int], neighbors: str = "rotation",
                 max_steps: int = 10_000, lookahead: int = 300) -> None:
        self.joint_model = joint_model
        self.phi_index = list(phi_index)
        self.turn_index = dict(turn_index)
        self.neighbors = neighbors
        self.max_steps = int(max_steps)
        self.lookahead = int(lookahead)
        self.result: CoverageResult | None = None

    @classmethod
    def for_env(cls, env, phi: object = 135.0, neighbors: str = "rotation",
                max_steps: int | None = None, lookahead: int = 300, cell_bins: int = 8,
                corner_rule: str = "no_squeeze") -> CoveragePlanPolicy:
        """The planner for a `MultiBounceEnv` (parallel form, discrete actions, tick mode).

        ``phi``: degrees, one for every robot or one per robot (docs/choices/multirobot.md, "One fixed bounce
        angle per robot"); each must be in that robot's angle set. The env's ``turn_angles`` must
        hold ±360°/bins for the neighbour jumps. ``max_steps`` defaults to the env's
        ``max_cycles``. The plan is made on ``env.cell_model(cell_bins, corner_rule)``: the cell
        backend's own model, or on continuous backends one with these bins and corner rule.
        """
        env = getattr(env, "unwrapped", env)
        _check_tick_mode(env, "CoveragePlanPolicy")
        model = env.cell_model(cell_bins, corner_rule)
        m = env.options.n_robots
        try:
            phis = [float(p) for p in np.broadcast_to(np.asarray(phi, dtype=float), (m,))]
        except ValueError:
            raise ConfigError(f"phi: expected one angle or {m} (one per robot), got {phi!r}") \
                from None
        jm = JointCellModel(model, phis, collisions=env.options.robot_collisions == "bounce",
                            min_sep_cells=env.options.min_sep_cells)
        phi_index = [_angle_index(env, i, p) for i, p in enumerate(phis)]
        width = 360.0 / model.n_bins
        turns = np.degrees(env.options.turn_angles)
        turn_index: dict[int, int] = {}
        for j, deg in enumerate(turns):
            bins = deg / width
            if abs(bins - round(bins)) < 1e-6:
                signed = (round(bins) + model.n_bins // 2) % model.n_bins - model.n_bins // 2
                turn_index.setdefault(signed, j)
        if 1 not in turn_index or -1 not in turn_index:
            raise ConfigError(f"turn_angles: the neighbour jumps need turn commands of "
                              f"±{width:g}°, got {turns.tolist()}")
        return cls(jm, phi_index, turn_index, neighbors,
                   env.max_cycles if max_steps is None else max_steps, lookahead)

    def start_options(self, env, seed: int) -> dict | None:
        """None on the cell backend (the env's random start is a joint cell); on continuous
        backends a random joint cell's centres and headings (`random_start`; docs/choices/multirobot.md,
        "Random initial joint cells")."""
        env = getattr(env, "unwrapped", env)
        if env.options.backend == "cell":
            return None
        centres, headings = self.joint_model.model.configuration(random_start(self.joint_model,
                                                                             seed))
        return {"start": {"position": centres.tolist(), "heading": headings.tolist()}}

    def reset(self, env) -> None:
        env = getattr(env, "unwrapped", env)
        state = env.robot_state
        start = self.joint_model.from_poses(state.position, np.degrees(state.heading))
        self.result = plan_coverage(self.joint_model, start, max_steps=self.max_steps,
                                    neighbors=self.neighbors, lookahead=self.lookahead,
                                    seed=0, stop_at_full=True)
        self.actions = self._compile(self.result, env)
        self.predicted_steps_to_full = self.result.steps_to_full
        if self.predicted_steps_to_full is not None \
                and self.predicted_steps_to_full > len(self.actions):
            self.predicted_steps_to_full = None  # the plan broke off before full coverage
        self.t = 0
        self.agents = list(env.possible_agents)

    def _compile(self, result: CoverageResult, env) -> list[list[int]]:
        """One action list per executable edge of x̃, stopping at the first edge no command tick
        can execute."""
        model = self.joint_model.model
        nb = model.n_bins
        actions: list[list[int]] = []
        for t, kind in enumerate(result.edge_kinds):
            if kind == "step":
                actions.append(list(self.phi_index))
                continue
            a, b = result.trajectory[t], result.trajectory[t + 1]
            (pa, ka), (pb, kb) = model.decode(a), model.decode(b)
            row = list(self.phi_index)
            if kind == "random" or np.any(pa != pb):
                break
            for i in np.flatnonzero(ka != kb):
                signed = (int(kb[i] - ka[i]) + nb // 2) % nb - nb // 2
                if signed not in self.turn_index:
                    return actions
                row[i] = len(env.options.angles[i]) + self.turn_index[signed]
            actions.append(row)
        return actions

    @property
    def executable_steps(self) -> int:
        """How many edges of x̃ the env executes (the rest of the episode: plain bouncing)."""
        return len(self.actions)

    def act(self, observations: dict, infos: dict) -> dict:
        row = self.actions[self.t] if self.t < len(self.actions) else self.phi_index
        self.t += 1
        return {a: row[i] for i, a in enumerate(self.agents) if a in observations}


def regions_of(env, model: CellModel) -> list[np.ndarray]:
    """The monitoring task's region polygons as position cells: the cells whose centre lies in
    (or on the boundary of) robot i's polygon."""
    import shapely

    task = env.task
    if getattr(task, "name", None) != "monitoring":
        raise ConfigError("MonitoringPlanPolicy: the env's task must be 'monitoring'")
    out = []
    for i, poly in enumerate(task.regions):
        inside = shapely.intersects_xy(poly, model.centres[:, 0], model.centres[:, 1])
        if not inside.any():
            raise ConfigError(f"regions[{i}]: contains no free cell centre of the cell model")
        out.append(np.flatnonzero(inside))
    return out


def in_region_share(result: MonitoringResult, g: int, regions, samples: int = 16) -> float:
    """The cell model's prediction of the monitoring task's ``in_region`` on accepted cycle
    ``g``: both robots move from cell centre to cell centre, one step per tick, around the
    cycle; the share of each tick a robot spends in (or on the boundary of) its region polygon
    — measured like the task, along the path, here at ``samples`` midpoints per tick —
    averaged over the ticks of the cycle and the two robots."""
    import shapely

    t = (np.arange(samples) + 0.5) / samples
    shares = []
    for z, poly in zip(result.split(result.cycles[g]), regions, strict=True):
        centre, _ = result.model.configuration(z)
        step = np.roll(centre, -1, axis=0) - centre
        points = (centre[:, None, :] + t[None, :, None] * step[:, None, :]).reshape(-1, 2)
        shares.append(shapely.intersects_xy(poly, points[:, 0], points[:, 1]).mean())
    return float(np.mean(shares))


def cycle_start(result: MonitoringResult, seed: int) -> tuple[int, int] | None:
    """The start on an accepted cycle of Algorithm 2 for ``seed``: accepted group ``seed mod r``,
    entered at its cycle cell ``(seed div r) mod period``, as ``(group, joint cell)``; ``None``
    when no group was accepted (r = 0). ``result.start_options(cell)`` places the robots there."""
    if result.r == 0:
        return None
    group = seed % result.r
    cycle = result.cycles[group]
    return group, int(cycle[(seed // result.r) % len(cycle)])


class MonitoringPlanPolicy(MultiPolicy):
    """Let two robots bounce with their φ_i, from the env's start or from an accepted cycle of
    Algorithm 2 (module docstring).

    ``result`` is the `MonitoringResult`; ``r`` the number of accepted groups; ``start`` one of
    `MONITORING_STARTS`. Its name is ``planner``, or ``planner (cycle start)`` when it picks its
    start. After `start_options` with ``start="cycle"``: ``group`` (index into
    ``result.cycles``), ``period``, ``start_cell`` and ``predicted_in_region`` (the cell model's
    time in own region on that cycle, `in_region_share`). They stay ``None`` with
    ``start="draw"`` (the model makes no prediction from an arbitrary start) and with r = 0
    (nothing to follow: the env draws the start and the robots bounce).
    """

    name = "planner"

    def __init__(self, result: MonitoringResult, phi_index: list[int],
                 start: str = MONITORING_STARTS[0]) -> None:
        if start not in MONITORING_STARTS:
            raise ConfigError(f"start: expected one of {list(MONITORING_STARTS)}, got {start!r}")
        self.result = result
        self.phi_index = list(phi_index)
        self.start = start
        if start == "cycle":
            self.name = "planner (cycle start)"
        self.group = self.period = self.start_cell = self.predicted_in_region = None

    @property
    def r(self) -> int:
        return self.result.r

    @classmethod
    def for_env(cls, env, phi: object = None, mode: str = "visit",
                forbid_swaps: bool | None = None, min_sep_cells: int | None = None,
                cell_bins: int = 8, corner_rule: str = "no_squeeze",
                start: str = MONITORING_STARTS[0]) -> MonitoringPlanPolicy:
        """The planner for a 2-robot monitoring `MultiBounceEnv` in tick mode.

        ``phi``: degrees, one for both robots or a pair (default: each robot's first angle).
        Regions: the task's polygons (`regions_of`). ``forbid_swaps`` defaults to whether the env's
        robots bounce off each other (a swap on the grid is then a conflict: docs/choices/multirobot.md,
        "Robot–robot conflicts on the grid"); ``min_sep_cells`` (the cycles' safety margin,
        `joint_monitoring_cycles`) to the env's. ``start``: one of `MONITORING_STARTS`.
        """
        env = getattr(env, "unwrapped", env)
        _check_tick_mode(env, "MonitoringPlanPolicy")
        if env.options.n_robots != 2:
            raise ConfigError(f"n_robots: Algorithm 2 is implemented for 2 robots, got "
                              f"{env.options.n_robots}")
        if phi is None:
            phis = [math.degrees(float(env.options.angles[i][0])) for i in range(2)]
        else:
            phis = [float(p) for p in np.broadcast_to(np.asarray(phi, dtype=float), (2,))]
        model = env.cell_model(cell_bins, corner_rule)
        if forbid_swaps is None:
            forbid_swaps = env.options.robot_collisions == "bounce"
        if min_sep_cells is None:
            min_sep_cells = env.options.min_sep_cells
        result = joint_monitoring_cycles(model, [math.radians(p) for p in phis], regions_of(env, model),
                                     mode=mode, forbid_swaps=forbid_swaps,
                                     min_sep_cells=min_sep_cells)
        return cls(result, [_angle_index(env, i, p) for i, p in enumerate(phis)], start)

    def cycle_options(self, seed: int) -> dict | None:
        """The reset options that place the robots at `cycle_start` for ``seed`` (``None`` with
        r = 0), whatever ``start`` is: what an experiment imposes on every policy to give them
        this planner's start."""
        chosen = cycle_start(self.result, seed)
        return None if chosen is None else self.result.start_options(chosen[1])

    def start_options(self, env, seed: int) -> dict | None:
        """``start="cycle"``: the `cycle_options` of ``seed``; ``start="draw"``: ``None`` (the
        env's draw)."""
        self.group = self.period = self.start_cell = self.predicted_in_region = None
        chosen = cycle_start(self.result, seed) if self.start == "cycle" else None
        if chosen is None:
            return None
        self.group, self.start_cell = chosen
        self.period = len(self.result.cycles[self.group])
        self.predicted_in_region = in_region_share(self.result, self.group,
                                                   getattr(env, "unwrapped", env).task.regions)
        return self.result.start_options(self.start_cell)

    def reset(self, env) -> None:
        self.agents = list(getattr(env, "unwrapped", env).possible_agents)

    def act(self, observations: dict, infos: dict) -> dict:
        return {a: self.phi_index[i] for i, a in enumerate(self.agents) if a in observations}
