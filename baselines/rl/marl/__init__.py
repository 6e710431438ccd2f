"""The multi-robot learners of the field, in torch: IPPO and MAPPO, each with or without
parameter sharing (``algo: ippo | mappo`` of a training configuration on a multi-robot env id,
`baselines.rl.train`).

They train on `bounce_gym.envs.team_vector_env.TeamVectorEnv` — B teams of m robots stepped as
numpy arrays, equal step for step to the PettingZoo env `MultiBounceEnv` — and are evaluated on
that PettingZoo env, each robot acting from its own observation (decentralised execution).

* **IPPO** (independent PPO; de Witt et al. 2020): each robot's critic sees what its actor sees,
  its own observation.
* **MAPPO** (Yu et al. 2022): the critic is centralised — it sees the global state
  (``TeamVectorEnv.state()``: every robot's pose), plus the robot's one-hot index when one
  critic serves every robot; the actor stays decentralised, so nothing but the robot's own
  observation is needed to act.
* ``share: true`` — one actor (and one critic) for every robot (parameter sharing; robots that
  should act differently need ``env_kwargs.agent_id: true``, their index in the observation);
  ``share: false`` — an actor and a critic per robot.

Why not a library: BenchMARL 1.5.2 pulls torchrl 0.11.1, tensordict, hydra-core, omegaconf,
torchvision and av, and replaces the pinned CPU build of torch 2.13 by torch 2.14.1 with some
fifteen CUDA packages (``pip install --dry-run benchmarl``); Stable-Baselines3 has no centralised
critic; JaxMARL's algorithms are single-file scripts, not a library API, and need JAX envs.

The modules, each with one job:

* `settings` — the hyperparameters and their ranges, checked before anything is built;
* `networks` — the actor and critic MLPs (orthogonal initialisation), their weights as arrays;
* `rollout` — the experience of B teams over ``n_steps``, the autoreset steps left out;
* `ppo` — GAE per robot and the clipped PPO updates;
* `runner` — the host loop of one seed: monitor file, checkpoints, the model file;
* `policy` — a saved model as the policy of every robot in the evaluation.
"""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
