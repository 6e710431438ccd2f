"""Figures of an evaluation run: the shared helpers (`figures`), every experiment's trajectories
(`trajectories`), the bounce-visibility figures (`visibility`) and the drifter planners' figures
(`drifters`); the families draw the rest."""
