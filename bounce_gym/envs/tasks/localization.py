"""Global localization from bumps and time."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bounce_gym.cells.bump_states import BumpStates
from bounce_gym.cells.outcomes import BumpOutcomes
from bounce_gym.dynamics.particles import DEFAULT_PARTICLES, ParticleBelief
from bounce_gym.dynamics.sampled_model import DEFAULT_SAMPLES
from bounce_gym.envs.tasks.base import Task
from bounce_gym.errors import ConfigError
from bounce_gym.markov.belief import BeliefFilter, with_heading_offsets
from bounce_gym.markov.filters import ActiveLocalizationFilter, LocalizationFilter
from bounce_gym.validate import flag, integer, number

#: The ``filter_factory`` that selects the built-in filter (`combinatorial_filter`).
COMBINATORIAL = "combinatorial"
#: The ``filter_factory`` that selects the belief filter on the env's sampled GCM.
BELIEF = "belief"
#: The ``filter_factory`` that selects the particle belief moved by the env's own dynamics.
PARTICLES = "particles"
#: default posterior mass of one decision state at which the belief filter claims it
DEFAULT_CLAIM_THRESHOLD = 0.99
#: default floor of the particle filter's effective sample size for a claim, a share of particles
DEFAULT_CLAIM_ESS = 0.1
#: default bumps in a row the particle filter's evidence must hold before it claims
DEFAULT_CLAIM_BUMPS = 2
#: default mass below which the particle filter's followed claim is withdrawn
DEFAULT_WITHDRAW_BELOW = 0.5
#: default independent particle sets besides the main one that must agree on a claim
DEFAULT_CLAIM_REPLICAS = 1
#: The methods a filter must have (``size`` and ``localized`` may appear only after ``reset``).
_FILTER_METHODS = ("reset", "update")


class LocalizationTask(Task):
    """Global localization: the robot starts at an unknown pose and senses only bumps and time.

    Args:
        filter_factory: ``"combinatorial"`` for the built-in filter (`combinatorial_filter`),
            ``"belief"`` for the histogram filter on the env's sampled GCM (below),
            ``"particles"`` for Monte Carlo localization with the env's own dynamics (below),
            or, from Python, a callable ``f(options) -> filter`` building a localization filter
            for the env's validated `EnvOptions`; None runs without one. No other string is
            accepted: an env's arguments often come from a configuration file, which is data
            and may not name code to import and run. A filter has ``reset()``,
            ``update(symbol, angle)`` — symbol 1 for a bump tick (``angle`` the bounce angle
            used, radians), 0 for a forward tick — and the attributes ``size`` (candidate
            configurations) and ``localized`` (in a knowledge cycle: localized up to the
            world's symmetry); optionally ``colour`` and ``trapped``.
        terminate_when_localized: end the episode once the filter reports ``localized``.
        tick_cost: cost per tick until the filter first reports ``localized`` (default 0.1,
            in the reward's unit, bits; must be > 0).
        claim_threshold: with ``"belief"`` or ``"particles"``, the posterior mass one decision state needs for the
            filter to claim it (default 0.99).
        model_samples: with ``"belief"``, sample points per decision state and angle of the
            sampled GCM (`BounceCore.sampled_model`, default 200).
        particles: with ``"particles"``, the number of particles (default 10,000).
        claim_ess: with ``"particles"``, the effective sample size a claim needs (a share of
            the particles, default 0.1; `ParticleClaims`).
        claim_bumps: with ``"particles"``, the bumps in a row a claim's evidence must hold
            (default 2).
        withdraw_below: with ``"particles"``, the followed mass below which a claim is
            withdrawn (default 0.5).
        claim_replicas: with ``"particles"``, the independent particle sets besides the main
            one that must agree on a claim (default 1).

    **Claims.** Every filter's ``localized`` is a claim, judged against the robot's true
    decision state at a bump (`bounce_gym.cells.bump_states`: the cell of the env's cell model
    holding the contact point, and the bin of the heading it drove with). ``info`` carries
    ``claims`` (claims made so far), ``wrong_claims`` (of them, those whose claim did not hold
    the true state at the bump they were made), ``wrong_claim`` (``wrong_claims`` > 0),
    ``withdrawn`` (claims withdrawn) and ``correct`` (below); all False or 0 until a claim is
    made, and for a user's filter without ``candidates``. The combinatorial, the belief and a
    user's filter claim once and never withdraw: ``correct`` (the claim is exactly the true
    state) is fixed at the bump of that claim. The combinatorial filter claims its candidate
    set once in a knowledge cycle (a set of several states — the world's symmetry — is
    neither correct nor wrong). The belief filter (`bounce_gym.markov.belief`, bounce steps and
    discrete actions only) is updated at every bump with the index of the angle commanded and
    the clock the robot reads there; the clock of the reset's drive is not used (the start
    pose is unknown, so the prior is uniform over the states the model has samples of). It
    claims its most likely state once that state's mass reaches ``claim_threshold``; ``info``
    then also carries ``claim``, and always ``belief_mass`` (the largest mass). Its reward is
    the drop in the belief's entropy (bits) minus ``tick_cost`` per tick until the claim.
    The particle filter (`ParticleClaims`, `bounce_gym.dynamics.particles`, backends with
    continuous headings — kinematic, pymunk ideal or dynamic physics —, bounce steps and
    discrete actions) starts from the global prior conditioned on the clock of the reset's
    drive and is updated with the angle commanded and the clock at each bump. Its claim is on
    the robot's state now: it is followed from bump to bump and may be withdrawn and made
    again (`ParticleClaims` has the rules), so its ``correct`` is judged at every bump (the
    standing claim is the true state; False while none stands) — at the episode's end, whether
    the claim standing then is right. It has the same ``claim`` and ``belief_mass``. With
    ``terminate_when_localized`` the episode ends at the first claim: the evidence a claim
    needs (mass, effective sample size, bumps in a row) is gathered before it is made, never
    after. Its generator is spawned from the env's (`numpy.random.Generator.spawn`: the env's
    own draws are not changed), so a seed fixes its claims.

    The task feeds the filter the tick stream: the forward ticks of the drive that ``reset`` made
    (bounce mode), then per step its bump tick first and its forward ticks after. Without a
    filter it gives no reward. Either way ``info`` carries what the robot sensed in the step just
    taken, ``info["observation"]`` = (bump ticks, clock, angle or None), None after ``reset``,
    and ``info["observation_count"]``, the steps taken since ``reset``; a user who wants the whole
    history collects it (the task keeps none, so a long episode costs the same per step).

    With a filter, ``info`` carries ``candidates``, ``localized`` (and ``colour``, ``trapped``),
    and from the tick the filter first reports ``localized`` on, ``ticks_to_localize`` (ticks
    since the episode began, the drive of a bounce-mode reset included). The reward of a step
    is the drop in log2(candidates) minus ``tick_cost`` per tick of the step up to that tick.
    The information term sums to log2(N_0 / N_T) whatever the policy (it is a potential
    difference), so the return of an episode that localizes is log2(N_0 / N_T) − tick_cost ×
    (its ticks to localize after the reset): of two episodes that localize from the same start,
    the faster one scores strictly higher. An episode that does not localize ends with at least
    two candidates (one bit short) and pays for every tick; in bounce mode every step takes at
    least one tick, so within the registered horizon of H steps every episode that localizes
    in fewer than H + 1 / tick_cost ticks outscores every episode that does not.
    """

    name = "localization"

    def __init__(self, filter_factory: Callable | str | None = None,
                 terminate_when_localized: bool = True, tick_cost: float = 0.1,
                 claim_threshold: float = DEFAULT_CLAIM_THRESHOLD,
                 model_samples: int = DEFAULT_SAMPLES,
                 particles: int = DEFAULT_PARTICLES, claim_ess: float = DEFAULT_CLAIM_ESS,
                 claim_bumps: int = DEFAULT_CLAIM_BUMPS,
                 withdraw_below: float = DEFAULT_WITHDRAW_BELOW,
                 claim_replicas: int = DEFAULT_CLAIM_REPLICAS) -> None:
        if filter_factory not in (None, COMBINATORIAL, BELIEF, PARTICLES) \
                and (isinstance(filter_factory, str) or not callable(filter_factory)):
            raise ConfigError(f"filter_factory: expected {COMBINATORIAL!r}, {BELIEF!r}, "
                              f"{PARTICLES!r}, None or "
                              f"(from Python) a callable, got {filter_factory!r}")
        self.filter_factory = filter_factory
        self.terminate_when_localized = flag("terminate_when_localized", terminate_when_localized)
        self.tick_cost = number("tick_cost", tick_cost, minimum=0.0, strict=True)
        self.claim_threshold = number("claim_threshold", claim_threshold, minimum=0.0,
                                      maximum=1.0, strict=True)
        self.model_samples = integer("model_samples", model_samples, minimum=2)
        self.particles = integer("particles", particles, minimum=1)
        self.claim_ess = number("claim_ess", claim_ess, minimum=0.0, maximum=1.0)
        self.claim_bumps = integer("claim_bumps", claim_bumps, minimum=1)
        self.withdraw_below = number("withdraw_below", withdraw_below, minimum=0.0, maximum=1.0)
        self.claim_replicas = integer("claim_replicas", claim_replicas, minimum=0)

    def configure(self, core) -> None:
        super().configure(core)
        self.states = BumpStates(core.cell_model())
        if self.filter_factory == BELIEF:
            self.filter = BeliefClaims(core, self.claim_threshold, self.model_samples)
        elif self.filter_factory == PARTICLES:
            self.filter = ParticleClaims(core, self.particles, ClaimRule(
                self.claim_threshold, self.claim_ess, self.claim_bumps, self.withdraw_below,
                self.claim_replicas))
        elif self.filter_factory == COMBINATORIAL:
            self.filter = combinatorial_filter(core)
        elif self.filter_factory is None:
            self.filter = None
        else:
            self.filter = self.filter_factory(self.options)
            missing = [m for m in _FILTER_METHODS if not callable(getattr(self.filter, m, None))]
            if missing:
                raise ConfigError(f"filter_factory: {self.filter_factory!r} returned "
                                  f"{self.filter!r}, not a localization filter (it lacks "
                                  f"{missing}; pass filter_factory=None to run without one)")

    def reset(self, state, rng, options):
        self.observation: tuple[int, int, float | None] | None = None
        self.observation_count = 0
        self.ticks_to_localize: int | None = None
        self.claims = self.wrong_claims = 0
        self.correct = False
        if isinstance(self.filter, BeliefClaims):
            self.filter.reset()
        elif isinstance(self.filter, ParticleClaims):
            self.filter.reset(rng.spawn(1)[0], int(state.clock[0]))
        elif self.filter is not None:
            self.filter.reset()
            for tick in range(int(state.clock[0])):  # the drive to the first contact (bounce)
                self._feed(0, None, tick + 1)
        return self._info()

    def _feed(self, symbol: int, angle: float | None, ticks: int) -> None:
        """One tick for the filter; ``ticks``: the episode's ticks once it is consumed."""
        self.filter.update(symbol, angle)
        if self.ticks_to_localize is None and self.filter.localized:
            self.ticks_to_localize = ticks

    def _info(self) -> dict:
        info = {"observation": self.observation, "observation_count": self.observation_count}
        if self.filter is not None:
            info.update(candidates=int(self.filter.size), localized=bool(self.filter.localized))
            for extra in ("colour", "trapped"):
                if hasattr(self.filter, extra):
                    info[extra] = getattr(self.filter, extra)
            if self.ticks_to_localize is not None:
                info["ticks_to_localize"] = self.ticks_to_localize
            withdrawn = self.filter.withdrawn if isinstance(self.filter, ParticleClaims) else 0
            info.update(correct=self.correct, wrong_claim=self.wrong_claims > 0,
                        claims=self.claims, wrong_claims=self.wrong_claims, withdrawn=withdrawn)
            if isinstance(self.filter, BeliefClaims | ParticleClaims):
                info["belief_mass"] = self.filter.max_mass
                if self.filter.claim is not None:
                    info["claim"] = self.filter.claim
        return info

    def _judge(self, state) -> None:
        """Judge a claim made at this bump, and the particle filter's standing claim."""
        follows = isinstance(self.filter, ParticleClaims)
        made = self.filter.made if follows else self.claims == 0 and self.filter.localized
        if follows and self.filter.claim is None:
            self.correct = False
        if not made and not (follows and self.filter.claim is not None):
            return
        truth = int(self.states.of(state.position[:1], state.heading[:1],
                                   np.nan_to_num(state.contact_normal[:1]))[0])
        claimed = np.asarray(self.filter.candidates)
        self.correct = claimed.size == 1 and int(claimed[0]) == truth
        if made:
            self.claims += 1
            self.wrong_claims += int(not np.isin(truth, claimed))

    def step(self, state, events):
        bumps = int(events.bumps[0])
        angle = None if math.isnan(events.angles[0]) else float(events.angles[0])
        self.observation = (bumps, int(state.clock[0]), angle)
        self.observation_count += 1
        reward, done = 0.0, False
        if isinstance(self.filter, BeliefClaims | ParticleClaims):
            before = self.filter.entropy
            self.filter.update(angle, int(state.clock[0]))
            charged = events.ticks if self.ticks_to_localize is None else 0
            if self.ticks_to_localize is None and self.filter.localized:
                self.ticks_to_localize = int(state.ticks)
            reward = before - self.filter.entropy - self.tick_cost * charged
            done = self.terminate_when_localized and self.filter.localized
        elif self.filter is not None:
            before = max(self.filter.size, 1)
            first = int(state.ticks) - events.ticks  # the episode's ticks before this step
            localized_before = self.ticks_to_localize is not None
            for tick in range(events.ticks):
                self._feed(1 if tick < bumps else 0, angle if tick < bumps else None,
                           first + tick + 1)
            if localized_before:
                charged = 0
            elif self.ticks_to_localize is None:
                charged = events.ticks
            else:  # localized in this step: the ticks up to and including that one
                charged = self.ticks_to_localize - first
            reward = (math.log2(before) - math.log2(max(self.filter.size, 1))
                      - self.tick_cost * charged)
            done = self.terminate_when_localized and bool(self.filter.localized)
        if self.filter is not None and hasattr(self.filter, "candidates"):  # a user's filter
            self._judge(state)  # may not name its claim
        return np.array([reward]), np.array([done]), self._info()


class _Claim:
    """A filter that claims one decision state, ``claim`` (None until it claims)."""

    claim: int | None = None

    @property
    def localized(self) -> bool:
        return self.claim is not None

    @property
    def candidates(self) -> np.ndarray:
        """The claimed state (empty before the claim)."""
        return np.array([] if self.claim is None else [self.claim], dtype=np.int64)


class BeliefClaims(_Claim):
    """The belief filter of the task (`LocalizationTask`, "Claims") on the env's sampled GCM:
    updated with the angle commanded and the clock at each bump, claiming its most likely
    decision state once that state's mass reaches ``threshold``."""

    def __init__(self, core, threshold: float, samples: int) -> None:
        options = core.options
        if options.action_type != "discrete" or options.step_mode != "bounce":
            raise ConfigError("localization filter 'belief': needs discrete actions and "
                              "step_mode='bounce' (it is updated once per bump, by angle index)")
        self.angles = np.asarray(options.angles[0], dtype=np.float64)
        self.filter = BeliefFilter(belief_outcomes(core, samples))
        self.n_states = core.cell_model().n_cells
        self.threshold = threshold
        self.reset()

    def reset(self) -> None:
        self.filter.reset()
        self.claim = None

    def update(self, angle: float | None, ticks: int) -> None:
        if angle is None:  # no bump in this step (not a bounce step): nothing to update
            return
        turn = np.mod(self.angles - angle + math.pi, 2 * math.pi) - math.pi
        self.filter.update(int(np.argmin(np.abs(turn))), ticks)
        if self.claim is None and self.max_mass >= self.threshold:
            self.claim = int(np.argmax(self.marginal))

    @property
    def marginal(self) -> np.ndarray:
        """(N,) the belief of each decision state, summed over the heading-offset classes."""
        return self.filter.belief.reshape(-1, self.n_states).sum(axis=0)

    @property
    def size(self) -> int:
        """Decision states with belief above 1e-6 (the reported ``candidates`` count)."""
        return int((self.marginal > 1e-6).sum())

    @property
    def entropy(self) -> float:
        return self.filter.entropy

    @property
    def max_mass(self) -> float:
        return float(self.marginal.max())


@dataclass(frozen=True)
class ClaimRule:
    """When the particle filter claims a decision state and when it withdraws the claim
    (`ParticleClaims`): the defaults were chosen on the tuning seeds
    (benchmarks/claim_rules.py, docs/localization_belief.md).

    Attributes:
        threshold: the mass one decision state needs.
        ess: the floor of the effective sample size, a share of the particles.
        bumps: bumps in a row at which the evidence must hold before the claim is made.
        withdraw_below: a standing claim is withdrawn once the mass that followed it falls
            below this.
        replicas: independent particle sets, besides the main one, that must agree.
    """

    threshold: float = DEFAULT_CLAIM_THRESHOLD
    ess: float = DEFAULT_CLAIM_ESS
    bumps: int = DEFAULT_CLAIM_BUMPS
    withdraw_below: float = DEFAULT_WITHDRAW_BELOW
    replicas: int = DEFAULT_CLAIM_REPLICAS


class ParticleClaims(_Claim):
    """The particle filter of the task (`LocalizationTask`, "Claims"): Monte Carlo localization
    moved by the env's own dynamics (`bounce_gym.dynamics.particles.ParticleBelief`, augmented
    MCL with sensor resetting), with claims that need evidence and are withdrawn when the
    belief turns against them.

    **Replicas.** Besides its main belief (``belief``, whose mass, entropy and candidates the
    task reports) the filter runs ``rule.replicas`` independent particle sets of the same size
    (``replicas``), fed the same angles and clocks, with generators spawned from its own. A
    confident wrong belief here is an artefact of one sample: the few particles near the true
    pose all died (particle deprivation, Probabilistic Robotics §4.3.4) and a group elsewhere
    that happened to fit the clocks took the mass — in the two wrong claims traced on the
    tuning seeds (9010, 9014; 1,000 particles, rotation noise) the true state held no mass
    from the 1st and the 14th bump on, while the wrong group fitted the clocks well (its w_avg
    rose to 0.5–0.9, so nothing was injected either). An independent set loses the truth
    independently and less often settles on the same wrong state at the same bump, so
    agreement is evidence a single set cannot give about the hypotheses it no longer holds. It
    is no proof: on recorded tuning episodes the replica removed 7 of 8 wrong claims
    (benchmarks/claim_rules.py), yet on the evaluation seeds both sets agreed on a wrong state
    in 4 of 200 episodes at 1,000 particles — once the truth is gone from both, the clocks can
    favour the same wrong hypothesis (docs/localization_belief.md).

    **Evidence.** At a bump the beliefs are *evident* for a state when in every one of them
    that state holds at least ``rule.threshold`` of the mass and the effective sample size of
    the measurement (`ParticleBelief.ess`) is at least ``rule.ess`` × particles. The ESS (not
    the count of distinct poses: after roughening every pose is distinct) says how many
    particles carried the mass: the audit of the first version found most wrong claims at mass
    1.00, held by the few particles that outlived the rest. Evidence followed for ``rule.bumps``
    bumps in a row — the next bump's evident state is where the particles of the last one went
    (`ParticleBelief.successors`), in every belief — makes the claim (``made`` is True at that
    update, ``claims_made`` counts it).

    **Withdrawal.** A standing claim is followed from bump to bump: it moves to the state that
    most of its particles reached. It is withdrawn (``withdrawn`` counts it) when, in any
    belief, that state holds less than ``rule.withdraw_below`` of the mass — the clock
    contradicted the claim, particles were injected in its place, or the belief was depleted
    and drawn anew (no particle then descends from the claim) —, when the beliefs follow it to
    different states, or when an ESS falls below the floor. A new claim then needs fresh
    evidence.
    """

    def __init__(self, core, particles: int, rule: ClaimRule | None = None) -> None:
        options = core.options
        if options.action_type != "discrete" or options.step_mode != "bounce":
            raise ConfigError("localization filter 'particles': needs discrete actions and "
                              "step_mode='bounce' (it is updated once per bump)")
        self.rule = ClaimRule() if rule is None else rule
        self.beliefs = [ParticleBelief(core.cell_model(), options.robot_dynamics, particles,
                                       max_clock=int(options.max_clock))
                        for _ in range(1 + self.rule.replicas)]
        self.belief, self.replicas = self.beliefs[0], self.beliefs[1:]
        self.claim: int | None = None

    def reset(self, rng: np.random.Generator, clock: int) -> None:
        for belief, stream in zip(self.beliefs, (rng, *rng.spawn(len(self.replicas))),
                                  strict=True):
            belief.reset(stream, clock)
        self.claim = None  # a claim is judged at a bump after a step: none at the reset
        self.pending: int | None = None  # the state of the evidence gathered so far
        self.streak = 0  # bumps in a row the evidence for ``pending`` held
        self.made = False
        self.claims_made = self.withdrawn = 0

    def update(self, angle: float | None, ticks: int) -> None:
        self.made = False
        if angle is None:  # no bump in this step: nothing to update
            return
        for belief in self.beliefs:
            belief.update(angle, ticks)
        if self.claim is not None:
            self.claim = self._follow(self.claim, self.rule.withdraw_below)
            self.withdrawn += self.claim is None
        if self.claim is None:
            self._gather()

    def _gather(self) -> None:
        """Evidence followed from the last bump, begun anew, or none; a claim once it held
        ``rule.bumps`` bumps in a row."""
        followed = None if self.pending is None \
            else self._follow(self.pending, self.rule.threshold)
        if followed is not None:
            self.pending, self.streak = followed, self.streak + 1
        elif (evident := self._evident()) is not None:
            self.pending, self.streak = evident, 1
        else:
            self.pending, self.streak = None, 0
        if self.streak >= self.rule.bumps:
            self.claim, self.made = self.pending, True
            self.claims_made += 1
            self.pending, self.streak = None, 0

    def _enough(self, belief: ParticleBelief) -> bool:
        """Whether the measurement's effective sample size reaches the floor."""
        return belief.ess >= self.rule.ess * belief.n

    def _evident(self) -> int | None:
        """The state every belief holds at least ``rule.threshold`` of its mass in, with the
        ESS floor reached; else None."""
        states = {belief.most_likely for belief in self.beliefs}
        if len(states) > 1 or not all(belief.max_mass >= self.rule.threshold
                                      and self._enough(belief) for belief in self.beliefs):
            return None
        return states.pop()

    def _follow(self, state: int, level: float) -> int | None:
        """The state the particles that were in ``state`` reached at the last bump, if in every
        belief they reached the same one, holding at least ``level`` of its mass with the ESS
        floor reached; else None."""
        reached = set()
        for belief in self.beliefs:
            states, mass = belief.successors(state)
            mass = np.where(states >= 0, mass, 0.0)
            if mass.size == 0 or mass.max() < level or not self._enough(belief):
                return None
            reached.add(int(states[np.argmax(mass)]))
        return reached.pop() if len(reached) == 1 else None

    @property
    def size(self) -> int:
        """Decision states holding particles (the reported ``candidates`` count)."""
        return int((self.belief.mass()[0] >= 0).sum())

    @property
    def entropy(self) -> float:
        return self.belief.entropy

    @property
    def max_mass(self) -> float:
        return self.belief.max_mass


#: heading-offset classes of the belief model: offsets within a bin, in bin widths
OFFSET_CLASSES = 9


def belief_outcomes(core, samples: int) -> BumpOutcomes:
    """The GCM the belief filter runs on: `OFFSET_CLASSES` sampled GCMs of the env, headings at
    evenly spaced offsets within the bins, joined over (offset class, decision state)
    (`bounce_gym.markov.belief.with_heading_offsets`: the offset is a hidden variable the
    bounces by whole bins keep)."""
    width = core.cell_model().bin_width
    offsets = (np.arange(OFFSET_CLASSES) + 0.5) / OFFSET_CLASSES * width - width / 2
    parts = [core.sampled_model(samples=samples, heading_offset=float(o)).outcomes
             for o in offsets]
    return with_heading_offsets(parts, offsets, width)


def combinatorial_filter(core) -> LocalizationFilter | ActiveLocalizationFilter:
    """The combinatorial filter of Alam, Bobadilla & Shell (2018) on the env's cell model.

    ``core`` is the env's `BounceCore`; the filter runs on ``core.cell_model()`` (cell size =
    ``step_length``, the env's ``cell_bins`` and ``corner_rule``, the robot's radius). One
    bounce angle gives the O(1) filter of the angle's DFA (thesis Ch. 2, Def. 8/9); several give
    the active filter over the angle set. The filter is closed-world only on the noise-free
    ``cell`` backend, where the robot steps the model exactly; elsewhere it is open-world and
    reports ``trapped`` once the robot's observations leave the model.
    """
    options = core.options
    if options.action_type != "discrete":
        raise ConfigError("localization filter: needs discrete actions (each bounce angle must "
                          "be a whole orientation bin of the cell model)")
    model = core.cell_model()
    exact = options.backend == "cell" and type(options.noise).__name__ == "Exact"
    angles = options.angles[0]
    if len(angles) == 1:
        return LocalizationFilter.from_model(model, float(angles[0]), open_world=not exact)
    return ActiveLocalizationFilter(model, angles, open_world=not exact)

