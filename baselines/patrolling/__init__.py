"""Alam (2018, thesis ch. 4): stochastic multi-robot patrolling — visibility covers and vulnerability."""
