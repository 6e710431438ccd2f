"""Figures of an evaluation run: the shared helpers (`figures`), every experiment's trajectories
(`trajectories`) and the bounce-visibility figures (`visibility`); the families draw the rest."""
