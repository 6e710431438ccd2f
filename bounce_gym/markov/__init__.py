"""Discrete dynamical systems shared by every family: the simple cell mapping (periodic groups,
transients), the generalized cell mapping (persistent groups, absorption, limiting
distributions), and the I-state automata and combinatorial filters built on a simple cell map."""

from bounce_gym.markov.automata import DFA, IStateNFA, build_dfa
from bounce_gym.markov.belief import BeliefFilter
from bounce_gym.markov.filters import ActiveLocalizationFilter, LocalizationFilter, WorldIdentifier
from bounce_gym.markov.gcm import GCMResult, gcm, generalized_cell_mapping, layer_gcm
from bounce_gym.markov.scm import SCMResult, scm, simple_cell_mapping
from bounce_gym.markov.ssp import ReachPlan

__all__ = [
    "DFA",
    "ActiveLocalizationFilter",
    "BeliefFilter",
    "GCMResult",
    "IStateNFA",
    "LocalizationFilter",
    "ReachPlan",
    "SCMResult",
    "WorldIdentifier",
    "build_dfa",
    "gcm",
    "generalized_cell_mapping",
    "layer_gcm",
    "scm",
    "simple_cell_mapping",
]
