"""Coverage with a bouncing robot (Alam, Bobadilla & Shell): the limiting distributions of the
bounce policies under noise, the optimal mixture α that matches a target distribution, and the
policy that runs the mixture in `bounce_gym.envs.BounceEnv`."""

from baselines.coverage.mixture import (
    MAX_EXACT,
    SPACES,
    MixtureResult,
    coverage_mixture,
    mixture_residual,
    optimal_mixture,
    policy_distributions,
    target_vector,
    to_grid,
)
from baselines.coverage.policy import DEFAULT_EPOCH, SCHEDULES, MixturePolicy

__all__ = ["DEFAULT_EPOCH", "MAX_EXACT", "SCHEDULES", "SPACES", "MixturePolicy", "MixtureResult",
           "coverage_mixture", "mixture_residual", "optimal_mixture", "policy_distributions",
           "target_vector", "to_grid"]
