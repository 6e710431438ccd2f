"""Learners written in JAX, trained end to end on the functional envs of `bounce_gym.jax`
(``algo: jax_ppo`` and ``algo: jax_dqn`` of a training configuration, `baselines.rl.train`).

The whole learning loop — the envs vmapped over ``n_envs``, their rollouts, the updates — is one
jitted function, scanned over a chunk of iterations; between chunks the host writes the monitor
rows and checkpoints (`baselines.rl.jaxrl.runner`). The modules, each with one job:

* `settings` — the hyperparameters each learner reads (SB3's names and defaults), their checks;
* `networks` — MLPs as plain parameter pytrees, orthogonal initialisation, flat observations;
* `ppo` — PPO with a clipped objective (Schulman et al. 2017) in the style of PureJaxRL
  (Lu et al. 2022);
* `replay` — a replay buffer of device arrays, with hindsight relabelling ("future" goals,
  Andrychowicz et al. 2017) for goal-conditioned envs;
* `dqn` — DQN (Mnih et al. 2015) on that buffer;
* `weights` — model files of weights (an ``.npz`` read without pickle) and their metadata;
* `runner` — the host loop of one seed: chunks, monitor file, checkpoints, the model file;
* `policy` — a saved JAX model as a `baselines.policy.Policy` for the evaluation.
"""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
