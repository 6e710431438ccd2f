"""One module per experiment family (`experiments.registry` lists them)."""
