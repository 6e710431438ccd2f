"""Analytic planners and reference policies for bounce_gym worlds.

The planners are in the subpackages (`baselines.navigation`, `baselines.coverage`, ...), each
exporting its own names; this package exports the policy interface they share
(`baselines.policy`).
"""

from baselines.policy import (
    CONTACT_AND_CLOCK,
    INFORMATION_CLASSES,
    POSE_OBSERVED,
    START_OBSERVED,
    FixedAnglePolicy,
    MultiPolicy,
    Policy,
    RandomAnglePolicy,
    labelled,
)

__all__ = ["CONTACT_AND_CLOCK", "INFORMATION_CLASSES", "POSE_OBSERVED", "START_OBSERVED",
           "FixedAnglePolicy", "MultiPolicy", "Policy", "RandomAnglePolicy", "labelled"]
