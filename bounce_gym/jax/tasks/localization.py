"""Localization (`bounce_gym.envs.tasks.localization.LocalizationTask`) with the combinatorial
filter, on the cell backend.

The filter's state is its candidate set, kept as a bool mask over the cell model's cells. It is
fed the tick stream the NumPy task feeds (the forward ticks of the reset's drive, then per step
its bump tick and its forward ticks); a tick with symbol s under the angle in use φ keeps the
candidates whose tick emits s and moves each to its φ-successor (Alam, Bobadilla & Shell 2018,
the filter's update; `ActiveLocalizationFilter.update`). Within one symbol the successor map is
one-to-one (a forward tick translates, a bump rotates in place), so the move is a gather through
the inverse map, tabulated per (angle, symbol); the tables check that property.

``localized`` is `ActiveLocalizationFilter.localized`: the candidates lie in one future class
(`bounce_gym.markov.automata.future_classes`) under every angle and are periodic
(`periodic_cells`) under the angle in use. With one angle this is "in a knowledge cycle" of the
angle's DFA, the test of `LocalizationFilter` (the differential tests compare both). A step
runs a fixed number of ticks (the longest step's) with the ticks past its own masked, so it
jits.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym.jax.tasks.base import CellFreeTask
from bounce_gym.markov.automata import future_classes, periodic_cells


class LocalizationParams(NamedTuple):
    source: jax.Array  # (n_angles, 2, n_cells): the cell a tick of symbol s under angle k moves
    #                    to each cell from (−1: none)
    classes: jax.Array  # (n_angles, n_cells) future class of each cell under each angle
    periodic: jax.Array  # (n_angles, n_cells) the cell is periodic under the angle
    truth: jax.Array  # (n_cells,) the decision state (`BumpStates`) of a robot in each cell
    tick_cost: jax.Array  # float32


class LocalizationState(NamedTuple):
    mask: jax.Array  # (n_cells,) the candidate set
    angle: jax.Array  # the angle in use (index)
    ticks_to_localize: jax.Array  # −1 before the filter first reports localized
    judged: jax.Array  # the claim has been judged
    correct: jax.Array
    wrong_claim: jax.Array


class CellLocalizationTask(CellFreeTask):
    """The localization task of ``task`` (a configured NumPy `LocalizationTask` with the
    combinatorial filter) on the cell model of ``robots`` (`CellRobots`); ``angles``: the
    actions' bounce angles (radians)."""

    name = "localization"

    def __init__(self, task, robots, angles: np.ndarray) -> None:
        if task.filter_factory != "combinatorial":
            raise ConfigError(
                f"bounce_gym.jax: localization with filter_factory={task.filter_factory!r} is "
                "not offered: the JAX env runs the combinatorial filter only (the belief and "
                "particle filters are posteriors moved by NumPy models, a user's filter is "
                "Python code, and without a filter the task has no reward to reproduce)")
        model = robots.model
        if model.n_cells != task.states.model.n_cells:
            raise ConfigError("bounce_gym.jax: the filter's cell model is not the robots'")
        self.terminate = task.terminate_when_localized
        #: the longest step's ticks: a bump and the longest drive
        self.max_ticks = int(robots.drive_ticks.max()) + 1
        self.n_cells = model.n_cells
        self._params = _tables(task, robots, angles)

    def params(self) -> LocalizationParams:
        return self._params

    # -- the filter -------------------------------------------------------------------------
    def _tick(self, mask, symbol, angle, params):
        source = params.source[angle, symbol]
        return (source >= 0) & mask[jnp.maximum(source, 0)]

    def _localized(self, mask, angle, params):
        classes = params.classes
        low = jnp.min(jnp.where(mask[None], classes, classes.shape[1]), axis=1)
        high = jnp.max(jnp.where(mask[None], classes, -1), axis=1)
        periodic = jnp.all(params.periodic[angle] | ~mask)
        return mask.any() & jnp.all(low == high) & periodic

    def _feed(self, state, count, bumps, first, params):
        """``count`` ticks (of at most `max_ticks`), the first ``bumps`` of them bump ticks;
        ``first``: the episode's ticks before them."""

        def tick(i, carry):
            mask, found = carry
            live = i < count
            moved = self._tick(mask, (i < bumps).astype(jnp.int32), state.angle, params)
            mask = jnp.where(live, moved, mask)
            now = live & (found < 0) & self._localized(mask, state.angle, params)
            return mask, jnp.where(now, first + i + 1, found)

        mask, found = jax.lax.fori_loop(0, self.max_ticks, tick,
                                        (state.mask, state.ticks_to_localize))
        return state._replace(mask=mask, ticks_to_localize=found)

    # -- episodes ---------------------------------------------------------------------------
    def start(self, drawn, start, z, ticks, params):
        false = jnp.bool_(False)
        state = LocalizationState(mask=jnp.ones(self.n_cells, bool), angle=jnp.int32(0),
                                  ticks_to_localize=jnp.int32(-1), judged=false, correct=false,
                                  wrong_claim=false)
        return self._feed(state, ticks, 0, jnp.int32(0), params)

    def step(self, state, step, params):
        before = jnp.maximum(state.mask.sum(), 1).astype(jnp.float32)
        first = step.episode_ticks - step.ticks
        was_localized = state.ticks_to_localize >= 0
        state = self._feed(state._replace(angle=step.action), step.ticks, 1, first, params)
        after = jnp.maximum(state.mask.sum(), 1).astype(jnp.float32)
        charged = jnp.where(was_localized, 0,
                            jnp.where(state.ticks_to_localize < 0, step.ticks,
                                      state.ticks_to_localize - first))
        reward = (jnp.log2(before) - jnp.log2(after)
                  - params.tick_cost * charged.astype(jnp.float32))
        localized = self._localized(state.mask, state.angle, params)
        judge = localized & ~state.judged
        truth = params.truth[step.after]
        state = state._replace(
            judged=state.judged | judge,
            correct=jnp.where(judge, (state.mask.sum() == 1) & state.mask[truth], state.correct),
            wrong_claim=jnp.where(judge, ~state.mask[truth], state.wrong_claim))
        terminated = localized if self.terminate else jnp.bool_(False)
        return state, reward, terminated, self._report(state, localized)

    def info(self, state, z, params):
        return self._report(state, self._localized(state.mask, state.angle, params))

    def _report(self, state, localized) -> dict:
        return {"candidates": state.mask.sum(), "localized": localized,
                "trapped": ~state.mask.any(), "ticks_to_localize": state.ticks_to_localize,
                "correct": state.correct, "wrong_claim": state.wrong_claim}


def _tables(task, robots, angles: np.ndarray) -> LocalizationParams:
    """The filter's tables for the actions' ``angles``, from the cell model's successor maps
    (`CellModel.successor`), and the true decision state of each cell (the task's
    `BumpStates`, of the pose the cell backend gives a robot in the cell)."""
    model = robots.model
    n = model.n_cells
    pairs = [model.successor(float(a)) for a in angles]
    bump = np.asarray(pairs[0][1], dtype=bool)
    source = np.full((len(angles), 2, n), -1, dtype=np.int64)
    classes = np.empty((len(angles), n), dtype=np.int64)
    periodic = np.empty((len(angles), n), dtype=bool)
    for k, (succ, _) in enumerate(pairs):
        succ = np.asarray(succ, dtype=np.int64)
        for symbol in (0, 1):
            cells = np.flatnonzero(bump == bool(symbol))
            if np.unique(succ[cells]).size != cells.size:
                raise ConfigError("bounce_gym.jax: a tick of one symbol moves two cells to one; "
                                  "the candidate mask cannot follow it")
            source[k, symbol, succ[cells]] = cells
        classes[k] = future_classes(succ, bump)
        periodic[k] = periodic_cells(succ)
    truth = task.states.of(robots.centre_of, robots.heading_of, robots.normal_of)
    return LocalizationParams(
        source=jnp.asarray(source, jnp.int32), classes=jnp.asarray(classes, jnp.int32),
        periodic=jnp.asarray(periodic),
        truth=jnp.asarray(truth, jnp.int32), tick_cost=jnp.float32(task.tick_cost))
