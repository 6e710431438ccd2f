"""Combinatorial localization filters (Alam, Bobadilla & Shell 2018)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

from bounce_gym.cells import CellModel
from bounce_gym.errors import ConfigError
from bounce_gym.markov.automata import (
    DFA,
    TRAP,
    ImpossibleObservationError,
    ObservationError,
    _read_only,
    _symbol,
    build_dfa,
    future_classes,
    periodic_cells,
)
from bounce_gym.worlds import World
from bounce_gym.worlds import get as get_world

# -- the filters (Def. 8, Def. 9) ----------------------------------------------------------------

class LocalizationFilter:
    """The closed-world (Def. 8) or open-world (Def. 9) combinatorial localization filter.

    It runs the DFA of `build_dfa`: one table lookup per observation. Protocol (as used by the
    localization task): ``reset()``, ``update(symbol)`` with 1 = bump tick and 0 = forward tick,
    and the attributes ``size`` and ``localized``.

    Attributes (read-only properties):
        state: current DFA state index (`TRAP` once trapped).
        candidates: the cells consistent with every observation so far (sorted ids; empty when
            trapped); valid before convergence too (docs/choices/localization.md, "Knowledge-cycle colours
            and numbering").
        size: ``len(candidates)``; once in a knowledge cycle, the uncertainty.
        colour: 1 outside knowledge cycles, 2 … m + 1 in cycle k, m + 2 in the trap (Defs. 8–9;
        numbering:
            docs/choices/localization.md, "Knowledge-cycle colours and numbering").
        localized: True once in a knowledge cycle (absorbing in the closed world).
        trapped: open world only — the observation string is impossible in this world ("not in
            E"). A closed-world filter raises `ImpossibleObservationError` instead and keeps its
            state.
        steps: the number of observations consumed since `reset`.
    """

    def __init__(self, dfa: DFA, open_world: bool = False, phi: float | None = None) -> None:
        if not isinstance(dfa, DFA):
            raise ConfigError(f"dfa: expected a DFA from build_dfa, got {type(dfa).__name__}")
        self.dfa = dfa
        self.open_world = bool(open_world)
        self.phi = phi  # the bounce angle the DFA was built for (radians), if known
        self._delta = dfa.delta.tolist()  # Python lists: the fastest O(1) lookup per symbol
        self._colour = dfa.colour.tolist()
        self._in_cycle = (dfa.cycle_of >= 0).tolist()
        self.reset()

    @classmethod
    def from_arrays(cls, successor, bump, open_world: bool = False) -> LocalizationFilter:
        return cls(build_dfa(successor, bump), open_world=open_world)

    @classmethod
    def from_model(cls, model: CellModel, phi: float, open_world: bool = False
                   ) -> LocalizationFilter:
        """The filter of a cell model for bounce angle ``phi`` (radians)."""
        return cls(build_dfa(*model.successor(phi)), open_world=open_world, phi=phi)

    @classmethod
    def for_world(cls, world: World | str, phi: float, n_bins: int = 8, cell_size: float = 1.0,
                  robot_radius: float = 0.0, open_world: bool = False,
                  corner_rule: str = "target_only") -> LocalizationFilter:
        """The filter of a world (or zoo name) discretised as in `bounce_gym.cells.CellModel`.

        ``phi`` is the bounce angle in radians (a multiple of 360° / ``n_bins``;
        docs/choices/cell_model.md, "Orientation bins and bounce angles").
        """
        if isinstance(world, str):
            world = get_world(world)
        model = CellModel(world, cell_size=cell_size, n_bins=n_bins, robot_radius=robot_radius,
                          corner_rule=corner_rule)
        return cls.from_model(model, phi, open_world=open_world)

    def reset(self) -> None:
        """Back to the start state: every cell is a candidate."""
        self._state = self.dfa.start
        self.steps = 0

    def update(self, symbol, angle: float | None = None) -> int:
        """Consume one observation (1 = bump tick, 0 = forward tick); returns the colour.

        ``angle`` (radians), the bounce angle of a bump, is optional; when given it must be the
        angle the filter was built for — a fixed-angle filter cannot follow another one.
        """
        a = _symbol(symbol)
        if angle is not None and self.phi is not None and not math.isclose(
                (angle - self.phi) % (2 * math.pi), 0.0, abs_tol=1e-9) and not math.isclose(
                (angle - self.phi) % (2 * math.pi), 2 * math.pi, abs_tol=1e-9):
            raise ObservationError(
                f"this filter was built for a bounce angle of {math.degrees(self.phi):g}°, "
                f"got {math.degrees(angle):g}°; use ActiveLocalizationFilter for several angles")
        if self._state != TRAP:
            nxt = self._delta[self._state][a]
            if nxt == TRAP and not self.open_world:
                raise ImpossibleObservationError(
                    f"closed-world filter: observation {a} after {self.steps} observations is "
                    f"impossible in this world (no candidate cell emits it); the robot cannot be "
                    f"in this world with these noise-free observations — use open_world=True to "
                    f"detect that")
            self._state = nxt
        self.steps += 1
        return self.colour

    def run(self, symbols: Iterable) -> int:
        """Consume a whole observation string; returns the final colour."""
        for a in symbols:
            self.update(a)
        return self.colour

    @property
    def state(self) -> int:
        return self._state

    @property
    def trapped(self) -> bool:
        return self._state == TRAP

    @property
    def candidates(self) -> np.ndarray:
        if self._state == TRAP:
            return np.empty(0, dtype=np.int64)
        return self.dfa.states[self._state]

    @property
    def size(self) -> int:
        return 0 if self._state == TRAP else int(self.dfa.states[self._state].size)

    @property
    def colour(self) -> int:
        return self.dfa.trap_colour if self._state == TRAP else self._colour[self._state]

    @property
    def localized(self) -> bool:
        return self._state != TRAP and self._in_cycle[self._state]

    @property
    def cycle(self) -> int | None:
        """Index of the current knowledge cycle (colour − 2), or None."""
        if self._state == TRAP or not self._in_cycle[self._state]:
            return None
        return int(self.dfa.cycle_of[self._state])


class WorldIdentifier:
    """Which of several candidate worlds can the robot be in? (Alam, Bobadilla & Shell 2018,
    Sec. III-C Problem 2 and Sec. IV-D)

    One open-world filter (Def. 9) per world runs in parallel on the same observation stream; a
    world is ruled out as soon as its filter is trapped. `identified` names the world once it is
    the only one left; ``possible == ()`` means the robot is in none of them.
    """

    def __init__(self, filters: Mapping[str, LocalizationFilter]) -> None:
        if not filters:
            raise ConfigError("filters: expected at least one candidate world")
        for name, filt in filters.items():
            if not isinstance(filt, LocalizationFilter) or not filt.open_world:
                raise ConfigError(f"filters[{name!r}]: expected an open-world LocalizationFilter")
        self.filters = dict(filters)
        self.reset()

    @classmethod
    def for_worlds(cls, worlds: Mapping[str, World] | Iterable[World | str], phi: float,
                   n_bins: int = 8, cell_size: float = 1.0, robot_radius: float = 0.0,
                   corner_rule: str = "target_only") -> WorldIdentifier:
        """Build the filters for worlds given as a name → World mapping or as Worlds/zoo names."""
        if not isinstance(worlds, Mapping):
            items = {}
            for w in worlds:
                if isinstance(w, str):
                    w = get_world(w)
                if w.name in items:
                    raise ConfigError(f"worlds: duplicate world name {w.name!r}")
                items[w.name] = w
            worlds = items
        return cls({name: LocalizationFilter.for_world(
            w, phi, n_bins=n_bins, cell_size=cell_size, robot_radius=robot_radius,
            open_world=True, corner_rule=corner_rule) for name, w in worlds.items()})

    def reset(self) -> None:
        for filt in self.filters.values():
            filt.reset()

    def update(self, symbol) -> tuple[str, ...]:
        """Feed one observation to every filter; returns the worlds still possible."""
        _symbol(symbol)
        for filt in self.filters.values():
            filt.update(symbol)
        return self.possible

    def run(self, symbols: Iterable) -> tuple[str, ...]:
        for a in symbols:
            self.update(a)
        return self.possible

    @property
    def possible(self) -> tuple[str, ...]:
        return tuple(name for name, f in self.filters.items() if not f.trapped)

    @property
    def ruled_out(self) -> tuple[str, ...]:
        return tuple(name for name, f in self.filters.items() if f.trapped)

    @property
    def identified(self) -> str | None:
        """The only world still possible, else None (several left, or none: not in any)."""
        left = self.possible
        return left[0] if len(left) == 1 else None


# -- beyond the paper: switching the bounce angle -------------------------------------------------

class _AngleSet:
    """Successor arrays of one cell model for several bounce angles (shared bump labels)."""

    def __init__(self, model: CellModel, angles: Sequence[float]) -> None:
        if not isinstance(model, CellModel):
            raise ConfigError(f"model: expected a CellModel, got {type(model).__name__}")
        try:
            angles = [float(a) for a in angles]
        except TypeError:
            raise ConfigError(f"angles: expected a sequence of angles in radians, got "
                              f"{angles!r}") from None
        if not angles:
            raise ConfigError("angles: expected at least one bounce angle")
        self.model = model
        self.angles = tuple(angles)
        self.bins = [model.angle_bins(a, "angles") % model.n_bins for a in angles]
        if len(set(self.bins)) != len(self.bins):
            raise ConfigError(f"angles: the angles must be distinct modulo 360°, got "
                              f"{[round(math.degrees(a), 6) for a in angles]}")
        pairs = [model.successor(a) for a in angles]  # raises ConfigError for φ ≡ 0
        self.successors = np.stack([s for s, _ in pairs])
        self.bump = pairs[0][1]  # whether a tick bumps does not depend on φ, only where it goes
        self.n_cells = model.n_cells

    def index(self, angle: float) -> int:
        bins = self.model.angle_bins(float(angle), "angle") % self.model.n_bins
        try:
            return self.bins.index(bins)
        except ValueError:
            raise ConfigError(
                f"angle: {math.degrees(angle):g}° is not one of the angles "
                f"{[round(math.degrees(a), 6) for a in self.angles]}") from None


class ActiveLocalizationFilter:
    """A localization filter for a robot that may change its bounce angle at every bump.

    It keeps the candidate set S (the cells consistent with all observations and the angles used)
    and on an observation ``symbol`` with angle φ in use applies
    ``S' = {c_φ(z) : z ∈ S, obs(z) = symbol}`` — O(|S|) per update. With one angle throughout it
    is exactly the DFA filter (`LocalizationFilter`) of that angle.

    Args:
        model: the cell model of the world.
        angles: the bounce angles (radians) the robot can rotate by reliably (Φ of thesis Ch. 3).
        angle: the angle in use initially (default: the first).
        open_world: on an impossible observation become `trapped` instead of raising
            `ImpossibleObservationError`.

    Attributes:
        candidates, size, trapped, steps: as in `LocalizationFilter`.
        converged: no further observation can shrink S under the current angle (all its cells
            are in one class of `future_classes`).
        localized: no angle can shrink S any more and S holds periodic cells of the current
            angle — for a robot with one angle exactly "in a knowledge cycle" of its DFA.
    """

    def __init__(self, model: CellModel, angles: Sequence[float], angle: float | None = None,
                 open_world: bool = False) -> None:
        self._set = _AngleSet(model, angles)
        self.model = model
        self.angles = self._set.angles
        self.open_world = bool(open_world)
        self._initial = 0 if angle is None else self._set.index(angle)
        self._per_angle: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.reset()

    def reset(self) -> None:
        self._cells = _read_only([np.arange(self._set.n_cells, dtype=np.int64)])[0]
        self._angle = self._initial
        self._trapped = False
        self.steps = 0

    @property
    def angle(self) -> float:
        """The bounce angle in use (radians); it applies at the next bump."""
        return self.angles[self._angle]

    def set_angle(self, angle: float) -> None:
        """Switch the bounce angle (one of ``angles``)."""
        self._angle = self._set.index(angle)

    def update(self, symbol, angle: float | None = None) -> int:
        """Consume one observation; on a 1 the robot rotates by ``angle`` (default: the angle in
        use, which ``angle`` also replaces). Returns the new candidate count."""
        a = _symbol(symbol)
        if angle is not None:
            self.set_angle(angle)
        if not self._trapped:
            cells = self._cells
            keep = cells[self._set.bump[cells] == bool(a)]
            if keep.size == 0:
                if not self.open_world:
                    raise ImpossibleObservationError(
                        f"closed-world active filter: observation {a} after {self.steps} "
                        f"observations is impossible in this world")
                self._trapped = True
                self._cells = keep
            else:
                nxt = self._set.successors[self._angle][keep]
                nxt.sort()
                nxt.flags.writeable = False
                self._cells = nxt
        self.steps += 1
        return self.size

    @property
    def candidates(self) -> np.ndarray:
        return self._cells

    @property
    def size(self) -> int:
        return int(self._cells.size)

    @property
    def trapped(self) -> bool:
        return self._trapped

    def _classes(self, k: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Future classes and periodic mask of angle ``k`` (default: the one in use), computed
        once per angle."""
        k = self._angle if k is None else k
        if k not in self._per_angle:
            succ = self._set.successors[k]
            self._per_angle[k] = future_classes(succ, self._set.bump), periodic_cells(succ)
        return self._per_angle[k]

    @property
    def converged(self) -> bool:
        if self._trapped:
            return False
        cls = self._classes()[0][self._cells]
        return bool((cls == cls[0]).all())

    @property
    def localized(self) -> bool:
        """No angle can shrink S any more (S is converged under every angle) and S holds
        periodic cells of the angle in use; with one angle, "in a knowledge cycle"."""
        if self._trapped:
            return False
        for k in range(len(self.angles)):
            cls = self._classes(k)[0][self._cells]
            if not (cls == cls[0]).all():
                return False
        return bool(self._classes()[1][self._cells].all())


