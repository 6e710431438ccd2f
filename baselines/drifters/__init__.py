"""The drifter planners of Alam 2018 (PhD thesis, ch. 5) on the cell model `DrifterCells`:

* `persistent_behavior` — Alg. 5.1, persistent and transient groups, absorption times;
* `deployment_locations` — Alg. 5.2, deployment cells that visit a whole layer, with the
  `random_deployment` and `greedy_deployment` baselines of the same size;
* `visibility_deployment` — Alg. 5.3, deployment for camera coverage of the seafloor;
* `persistent_reachability` — Alg. 5.4, the cells reachable across layers from a release cell;
* `value_iteration` — Alg. 5.5, the navigation policy to a goal, `reach_probability` of a policy,
  and `ValueIterationPolicy`, which runs it in ``bounce_gym/Drifter-v0`` (with the
  `AlwaysDriftPolicy` and `RandomLayerPolicy` baselines); `deploy_cells` turns a deployment
  into the ``deploy`` argument of ``bounce_gym/MultiDrifter-v0``, and `DeploymentPolicy`
  releases that env's fleet at a deployment and lets it drift;
* `horizon_plan` — finite-horizon value iteration for reaching a goal on a sampled GCM of the
  env's own dynamics (`bounce_gym.cells.SampledDrifterCells`), and `HorizonReachPolicy`, which
  acts on it from the drifter's observation.

Every planner returns plain data (numpy arrays of model states in small frozen dataclasses).
"""

from baselines.drifters.behavior import PersistentBehavior, persistent_behavior
from baselines.drifters.deployment import (
    Deployment,
    deploy_cells,
    deployment_locations,
    group_coverage,
)
from baselines.drifters.deployment_baselines import (
    expected_coverage,
    greedy_deployment,
    random_deployment,
    visit_probabilities,
)
from baselines.drifters.fleet import DEPLOYMENT_METHODS, DeploymentPolicy
from baselines.drifters.horizon_plan import HorizonPlan, HorizonReachPolicy, horizon_plan
from baselines.drifters.policy import AlwaysDriftPolicy, RandomLayerPolicy, ValueIterationPolicy
from baselines.drifters.reachability import (
    DrifterReachability,
    persistent_reachability,
    three_d_graph,
)
from baselines.drifters.value_iteration import (
    ValueIterationResult,
    goal_states,
    policy_matrix,
    reach_probability,
    value_iteration,
)
from baselines.drifters.visibility import (
    VisibilityDeployment,
    visibility_deployment,
    visible_cells,
)

__all__ = ["DEPLOYMENT_METHODS", "AlwaysDriftPolicy", "Deployment", "DeploymentPolicy",
           "HorizonPlan", "HorizonReachPolicy", "horizon_plan",
           "PersistentBehavior", "RandomLayerPolicy", "DrifterReachability", "ValueIterationPolicy",
           "ValueIterationResult", "VisibilityDeployment", "deploy_cells",
           "deployment_locations", "expected_coverage", "goal_states", "greedy_deployment",
           "group_coverage", "persistent_behavior", "persistent_reachability", "policy_matrix",
           "random_deployment", "reach_probability", "three_d_graph", "value_iteration",
           "visibility_deployment", "visible_cells", "visit_probabilities"]
