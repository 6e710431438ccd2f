"""Discrete dynamical systems shared by every family: the simple cell mapping (periodic groups,
transients), the generalized cell mapping (persistent groups, absorption, limiting
distributions), and the I-state automata and combinatorial filters built on a simple cell map."""
