"""One module per experiment family (`bounce_gym_experiments.registry` lists them)."""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
