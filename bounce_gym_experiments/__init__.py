"""Experiments: configurations, the episode runner, per-family metrics and plots, reports."""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
