"""Stochastic multi-robot patrolling (Alam 2018, thesis ch. 4): the cell graph of a World, random
walks with their hitting and commute times, and MAECT strategies. Every planner takes a networkx
graph and returns plain data (edge -> weight, a transition matrix with its node order)."""
