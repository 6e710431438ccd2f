"""Figures of an evaluation run: the shared helpers (`figures`), every experiment's trajectories
(`trajectories`), the bounce-visibility figures (`visibility`) and the drifter planners' figures
(`drifters`); the families draw the rest."""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
