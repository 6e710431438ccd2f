"""I-state automata of a simple cell map (Alam, Bobadilla & Shell 2018)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from bounce_gym.errors import BounceGymError, ConfigError
from bounce_gym.markov.scm import simple_cell_mapping

if TYPE_CHECKING:  # networkx is imported where a graph is built (~0.15 s an env does not need)
    import networkx as nx

TRAP = -1
"""State index of the implicit trap state (Def. 9); `DFA.delta` holds it for missing transitions."""

_SYMBOLS = {0: 0, 1: 1}  # also matches False/True and numpy integers/bools (equal hash and value)


class ObservationError(BounceGymError):
    """An observation symbol is not 0 (forward tick) or 1 (bump tick)."""


class ImpossibleObservationError(ObservationError):
    """A closed-world filter received an observation string no cell of its world can produce.

    Problem 1 assumes the robot is inside E, so this cannot happen with noise-free observations
    from that world; use ``open_world=True`` (Def. 9) to detect "not in E" instead.
    """


def _symbol(symbol) -> int:
    try:
        return _SYMBOLS[symbol]
    except (KeyError, TypeError):
        raise ObservationError(
            f"symbol: expected 0 (forward tick) or 1 (bump tick), got {symbol!r}") from None


# -- the SCM as arrays ---------------------------------------------------------------------------

def _check_scm(successor, bump) -> tuple[np.ndarray, np.ndarray]:
    succ = np.asarray(successor)
    obs = np.asarray(bump)
    if succ.ndim != 1 or succ.size == 0 or not np.issubdtype(succ.dtype, np.integer):
        raise ConfigError(f"successor: expected a non-empty 1-D integer array, got shape "
                          f"{succ.shape} and dtype {succ.dtype}")
    if obs.shape != succ.shape:
        raise ConfigError(f"bump: expected shape {succ.shape} like successor, got {obs.shape}")
    if obs.dtype != bool:
        if not np.isin(obs, (0, 1)).all():
            raise ConfigError("bump: expected booleans or 0/1 (1 = bump tick)")
        obs = obs.astype(bool)
    n = succ.size
    if succ.min() < 0 or succ.max() >= n:
        raise ConfigError(f"successor: every entry must be a cell id in [0, {n})")
    return succ.astype(np.int64, copy=False), obs


def periodic_cells(successor) -> np.ndarray:
    """Boolean mask of the periodic cells (Def. 1: ``z = C^m(z)`` for some m ≥ 1).

    The cells on the cycles of the functional graph, as found by `simple_cell_mapping`.
    """
    return simple_cell_mapping(np.asarray(successor, dtype=np.int64)).periodic


def periodic_groups(successor) -> tuple[np.ndarray, int]:
    """Group number of every cell and the number r of periodic groups (Def. 3, Def. 4).

    Each weakly connected component of the functional graph holds exactly one periodic group (its
    cycle) and that group's transient trajectories; `simple_cell_mapping` finds them. Here groups
    are renumbered 0 … r − 1 in order of the smallest cell id of their basin (periodic or
    transient), which is the order in which Algorithm 1's loop over the cells discovers them.
    """
    result = simple_cell_mapping(np.asarray(successor, dtype=np.int64))
    group, r = result.group.astype(np.int64), result.n_groups
    first = np.full(r, group.size, dtype=np.int64)
    np.minimum.at(first, group, np.arange(group.size, dtype=np.int64))
    rank = np.empty(r, dtype=np.int64)
    rank[np.argsort(first)] = np.arange(r)
    return rank[group], int(r)


def future_classes(successor, bump) -> np.ndarray:
    """Coarsest partition of the cells into classes with identical future observation strings.

    Moore's partition refinement on the labelled functional graph: start from the label classes
    and split by the class of the successor until stable. Two cells of one class can never be told
    apart by any further observation (the cell-level counterpart of a knowledge cycle).
    """
    succ, obs = _check_scm(successor, bump)
    cls = obs.astype(np.int64)
    count = int(np.unique(cls).size)
    while True:
        _, new = np.unique(cls * (count + 1) + cls[succ], return_inverse=True)
        new = new.reshape(-1).astype(np.int64)
        new_count = int(new.max()) + 1
        if new_count == count:
            return new
        cls, count = new, new_count


# -- I-state graphs (Def. 5) and the nondeterministic automaton (Def. 6) -------------------------

def istate_graph(successor, bump, group: int | None = None) -> nx.DiGraph:
    """The I-state graph with 0/1 edge labels (Def. 5; BUILD-STATEGRAPH of Algorithm 1).

    Vertices are cells (node attributes ``periodic`` and ``group``), edges ``(z, C(z))`` with the
    attribute ``label`` = 1 for a bump tick, 0 for a forward tick (docs/choices/cell_model.md,
    "Observation 1 means the orientation bin changed"). Without ``group`` the graph
    holds all N cells (the disjoint union of the groups' graphs, ``|G.V| = N``); with ``group = j``
    only periodic group j (numbered as in `periodic_groups`) and its transient trajectories.
    """
    succ, obs = _check_scm(successor, bump)
    periodic = periodic_cells(succ)
    groups, r = periodic_groups(succ)
    cells = np.arange(succ.size)
    if group is not None:
        if isinstance(group, bool) or not isinstance(group, int | np.integer) \
                or not 0 <= group < r:
            raise ConfigError(f"group: expected an integer in [0, {r}), got {group!r}")
        cells = cells[groups == group]
    import networkx as nx

    graph = nx.DiGraph(group=group, n_groups=r)
    graph.add_nodes_from((int(z), {"periodic": bool(periodic[z]), "group": int(groups[z])})
                         for z in cells)
    graph.add_edges_from((int(z), int(succ[z]), {"label": int(obs[z])}) for z in cells)
    if group is not None:
        graph.graph["period"] = int(periodic[cells].sum())
    return graph


def istate_graphs(successor, bump) -> list[nx.DiGraph]:
    """One I-state graph per periodic group, G = {G_1 … G_r} as returned by Algorithm 1."""
    _, r = periodic_groups(np.asarray(successor, dtype=np.int64))
    return [istate_graph(successor, bump, group=j) for j in range(r)]


@dataclass(frozen=True)
class IStateNFA:
    """The nondeterministic I-state automaton A = (Q, Σ_ε, δ, q0, F) of Def. 6, kept implicit.

    Q = {q0} ∪ cells (``size == N + 1``); q0 (`START`) has ε-moves to every cell and no labelled
    move; every cell q has exactly one labelled move, to C(q) on ℓ(q, C(q)) (so
    ``|δ(q, 0)| + |δ(q, 1)| = 1``); F = the periodic cells. Nothing returns to q0.
    """

    successor: np.ndarray
    bump: np.ndarray

    START = -1

    @classmethod
    def from_arrays(cls, successor, bump) -> IStateNFA:
        succ, obs = _check_scm(successor, bump)
        return cls(succ, obs)

    @property
    def n_cells(self) -> int:
        return int(self.successor.size)

    @property
    def size(self) -> int:
        """|Q| = N + 1 (Table I, "NFA states")."""
        return self.n_cells + 1

    nfa_size = size

    @property
    def final(self) -> np.ndarray:
        """F = G.V_P, the periodic cells (boolean mask)."""
        return periodic_cells(self.successor)

    def delta(self, q: int, symbol) -> frozenset[int]:
        """δ(q, a) for a labelled symbol a ∈ {0, 1} (the empty set where undefined)."""
        a = _symbol(symbol)
        if q == self.START:
            return frozenset()
        if not 0 <= q < self.n_cells:
            raise ConfigError(f"q: expected START or a cell id in [0, {self.n_cells}), got {q!r}")
        return frozenset({int(self.successor[q])}) if int(self.bump[q]) == a else frozenset()

    def epsilon_closure(self, states: Iterable[int]) -> frozenset[int]:
        """ε-Closure: q0 adds every cell (and itself); cells have no ε-moves."""
        states = frozenset(int(q) for q in states)
        if self.START in states:
            return states | frozenset(range(self.n_cells))
        return states


# -- the DFA (Def. 7) ----------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class DFA:
    """The deterministic I-state automaton A' of Def. 7 with its knowledge cycles and colours.

    Attributes:
        states: the states as sorted cell-id arrays; state 0 is the start state (all N cells;
            docs/choices/localization.md, "DFA size: the start state is all cells, the trap is not counted").
        delta: (n_states, 2) next state on 0 and on 1; `TRAP` (−1) where the transition is missing.
        n_cells: N.
        periodic: periodic cells of the SCM (None for a closed-loop `build_policy_dfa`).
        cycles: the knowledge cycles, each the state indices in transition order starting at the
            state holding the cycle's smallest cell id; numbered by (smallest cell id, first state).
        cycle_of: knowledge cycle index of every state, −1 outside the cycles.
        colour: colour of every state (docs/choices/localization.md, "Knowledge-cycle colours and
            numbering"): 1 outside the cycles, 2 + cycle index inside.
        bump_angle: for `build_policy_dfa`, the angle (radians) used on a 1 in every state
            (NaN where a 1 is impossible); None for a fixed-angle DFA.
        bump_angle_index: the same as an index into the planner's angles (−1 where impossible).
    """

    states: tuple[np.ndarray, ...]
    delta: np.ndarray
    n_cells: int
    periodic: np.ndarray | None
    cycles: tuple[np.ndarray, ...]
    cycle_of: np.ndarray
    colour: np.ndarray
    bump_angle: np.ndarray | None = None
    bump_angle_index: np.ndarray | None = None
    _index: dict = field(default_factory=dict, repr=False)

    start = 0

    # -- sizes and bookkeeping (docs/choices/localization.md, "DFA size: ...") --
    @property
    def n_states(self) -> int:
        """|Q'| without the implicit trap (the count reported next to Table I)."""
        return len(self.states)

    @property
    def has_trap(self) -> bool:
        """Whether some transition is missing, i.e. the open-world trap q_t is reachable."""
        return bool((self.delta == TRAP).any())

    @property
    def n_states_with_trap(self) -> int:
        """|Q'| counting the trap state q_t when some transition leads to it (Def. 9)."""
        return self.n_states + int(self.has_trap)

    @property
    def nfa_size(self) -> int:
        """|Q| = N + 1 of the nondeterministic automaton it was built from (Def. 6)."""
        return self.n_cells + 1

    @property
    def sizes(self) -> np.ndarray:
        """|S| of every state."""
        return np.array([s.size for s in self.states], dtype=np.int64)

    @property
    def final(self) -> np.ndarray | None:
        """F' = {S : S ∩ F ≠ ∅} as a boolean mask over states (kept for completeness:
        docs/choices/localization.md, "Final states are kept but unused")."""
        if self.periodic is None:
            return None
        return np.array([bool(self.periodic[s].any()) for s in self.states])

    @property
    def out_degree(self) -> np.ndarray:
        return (self.delta != TRAP).sum(axis=1)

    # -- knowledge cycles and colours (Defs. 8-9; docs/choices/localization.md) --
    @property
    def n_cycles(self) -> int:
        return len(self.cycles)

    @property
    def cycle_lengths(self) -> tuple[int, ...]:
        return tuple(len(c) for c in self.cycles)

    @property
    def uncertainties(self) -> tuple[int, ...]:
        """|S| of every knowledge cycle (the number of candidate configurations, Table II)."""
        return tuple(int(self.states[c[0]].size) for c in self.cycles)

    @property
    def min_uncertainty(self) -> int:
        """The "strongest possible localization" (Table II minimum)."""
        return min(self.uncertainties)

    @property
    def max_uncertainty(self) -> int:
        """The weakest localization a run can end with (Table II maximum)."""
        return max(self.uncertainties)

    @property
    def trap_colour(self) -> int:
        """Colour of the open-world trap q_t: #cycles + 2 (docs/choices/localization.md, "Knowledge-cycle colours
        and numbering")."""
        return self.n_cycles + 2

    def n_colours(self, open_world: bool = False) -> int:
        """Colours the filter uses: white + one per cycle (+ the trap in the open world)."""
        return self.n_cycles + 1 + int(open_world)

    # -- use --
    def step(self, state: int, symbol) -> int:
        """δ'(state, symbol); `TRAP` is absorbing."""
        if state == TRAP:
            return TRAP
        return int(self.delta[state, _symbol(symbol)])

    def run(self, symbols: Iterable, state: int = 0) -> int:
        """The state after reading ``symbols`` from ``state`` (`TRAP` if impossible)."""
        for a in symbols:
            state = self.step(state, a)
        return state

    def state_of(self, cells) -> int | None:
        """Index of the state whose cell set is ``cells``, or None if it is not a state."""
        key = np.unique(np.asarray(cells, dtype=np.int64)).tobytes()
        return self._index.get(key)

    def graph(self, with_trap: bool = False) -> nx.DiGraph:
        """The DFA as a networkx graph: nodes carry ``size`` and ``colour``, edges ``label``.

        With ``with_trap`` the trap is node `TRAP` with a self-loop on 0 and 1 (Def. 9). A
        DiGraph keeps one edge per pair, so an edge taken on both symbols has ``label = (0, 1)``.
        """
        import networkx as nx

        graph = nx.DiGraph()
        graph.add_nodes_from((i, {"size": int(s.size), "colour": int(self.colour[i])})
                             for i, s in enumerate(self.states))
        edges = [(int(i), int(self.delta[i, a]), a) for i in range(self.n_states) for a in (0, 1)
                 if self.delta[i, a] != TRAP or with_trap]
        for src, dst, a in edges:
            if graph.has_edge(src, dst):  # both symbols lead to the same state (e.g. the trap)
                graph.edges[src, dst]["label"] = (0, 1)
            else:
                graph.add_edge(src, dst, label=a)
        if with_trap and self.has_trap:
            graph.nodes[TRAP].update(size=0, colour=self.trap_colour)
            graph.add_edge(TRAP, TRAP, label=(0, 1))
        return graph

    def summary(self) -> dict:
        """Plain numbers for tables: NFA/DFA sizes, cycles, uncertainties and colours."""
        return {
            "nfa_states": self.nfa_size,
            "dfa_states": self.n_states,
            "dfa_states_with_trap": self.n_states_with_trap,
            "knowledge_cycles": self.n_cycles,
            "cycle_lengths": self.cycle_lengths,
            "uncertainties": self.uncertainties,
            "min_uncertainty": self.min_uncertainty,
            "max_uncertainty": self.max_uncertainty,
        }


def _subset_construction(n_cells: int, image: Callable[[np.ndarray, int], np.ndarray],
                         max_states: int | None):
    """Lazy (reachable-only) subset construction from the set of all cells (Alam, Bobadilla &
    Shell 2018, Sec. IV-C, Def. 7).

    ``image(S, a)`` returns the sorted, duplicate-free successor set of S on symbol a.
    """
    start = np.arange(n_cells, dtype=np.int64)
    states = [start]
    index = {start.tobytes(): 0}
    delta: list[tuple[int, int]] = []
    i = 0
    while i < len(states):
        row = [TRAP, TRAP]
        for a in (0, 1):
            nxt = image(states[i], a)
            if nxt.size == 0:
                continue  # the implicit trap
            key = nxt.tobytes()
            j = index.get(key)
            if j is None:
                j = index[key] = len(states)
                states.append(nxt)
                if max_states is not None and len(states) > max_states:
                    raise ConfigError(f"max_states: the DFA exceeds {max_states} states")
            row[a] = j
        delta.append((row[0], row[1]))
        i += 1
    return tuple(states), np.array(delta, dtype=np.int64).reshape(-1, 2), index


def _read_only(arrays: Iterable[np.ndarray]) -> tuple[np.ndarray, ...]:
    out = tuple(arrays)
    for a in out:
        a.flags.writeable = False  # filters hand these out as `candidates`
    return out


def _knowledge_cycles(states: tuple[np.ndarray, ...], delta: np.ndarray):
    """Knowledge cycles = SCCs of the DFA graph with > 1 state or a self-loop (Alam, Bobadilla &
    Shell 2018, Sec. IV-D).

    Every such SCC is a simple cycle: sizes never grow along an edge, so they are constant in an
    SCC, and a state whose two transitions are both defined loses cells on each of them.
    """
    import networkx as nx

    graph = nx.DiGraph()
    graph.add_nodes_from(range(len(states)))
    src, sym = np.nonzero(delta != TRAP)
    graph.add_edges_from(zip(src.tolist(), delta[src, sym].tolist(), strict=True))
    found = []
    for scc in nx.strongly_connected_components(graph):
        members = sorted(scc)
        if len(members) == 1 and not graph.has_edge(members[0], members[0]):
            continue
        smallest = [int(states[s][0]) for s in members]  # states are sorted arrays
        first = members[int(np.argmin(smallest))]  # ties: the lowest state index (argmin's first)
        order = [first]
        nxt = [t for t in graph.successors(first) if t in scc]
        while nxt[0] != first:
            order.append(nxt[0])
            nxt = [t for t in graph.successors(nxt[0]) if t in scc]
        if len(order) != len(members):  # pragma: no cover - excluded by the argument above
            raise AssertionError("a knowledge component is not a simple cycle")
        found.append((min(smallest), first, np.array(order, dtype=np.int64)))
    found.sort(key=lambda item: (item[0], item[1]))
    cycles = tuple(order for _, _, order in found)
    cycle_of = np.full(len(states), -1, dtype=np.int64)
    for k, order in enumerate(cycles):
        cycle_of[order] = k
    colour = np.where(cycle_of >= 0, cycle_of + 2, 1)
    return cycles, cycle_of, colour


def build_dfa(successor, bump, *, max_states: int | None = None) -> DFA:
    """The DFA A' of Def. 7 by lazy subset construction, with knowledge cycles and colours.

    Args:
        successor: the SCM C as an (N,) array of successor cell ids.
        bump: (N,) observation of every cell's tick (True/1 = bump, the label ℓ(z, C(z))).
        max_states: raise `ConfigError` if the DFA grows beyond this many states (Prop. 1 only
            bounds it by O(N²)).

    Per state the image on both symbols is one vectorised gather: S' = sort(C[S[ℓ[S] = a]]),
    de-duplicated (a cell-model SCM is injective on each label class, so nothing merges then).
    """
    succ, obs = _check_scm(successor, bump)
    dtype = np.int32 if succ.size < 2**31 else np.int64

    def image(cells: np.ndarray, a: int) -> np.ndarray:
        out = succ[cells[obs[cells] == bool(a)]]
        out.sort()
        if out.size > 1 and (out[1:] == out[:-1]).any():
            out = np.unique(out)
        return out

    states, delta, index = _subset_construction(succ.size, image, max_states)
    states = _read_only(s.astype(dtype) for s in states)
    cycles, cycle_of, colour = _knowledge_cycles(states, delta)
    return DFA(states=states, delta=delta, n_cells=int(succ.size),
               periodic=periodic_cells(succ), cycles=cycles, cycle_of=cycle_of, colour=colour,
               _index=index)

