"""Analytic planners and reference policies for bounce_gym worlds.

The planners are in the subpackages (`baselines.navigation`, `baselines.coverage`, ...), each
exporting its own names; this package exports the policy interface they share
(`baselines.policy`).
"""

from baselines.policy import FixedAnglePolicy, MultiPolicy, Policy, RandomAnglePolicy

__all__ = ["FixedAnglePolicy", "MultiPolicy", "Policy", "RandomAnglePolicy"]
