"""One module per experiment family (`bounce_gym_experiments.registry` lists them)."""
