"""Stochastic multi-robot patrolling against an adversary (Alam 2018, thesis ch. 4) as a
PettingZoo environment: `PatrolEnv` (``bounce_gym/Patrol-v0``) on the cell graph of a World,
with the board (graph, compass neighbours, visibility), its options, the exact capture
probabilities of a Markov patrol strategy and the renderer in their own modules."""

from bounce_gym.envs.patrol.env import PatrolEnv

__all__ = ["PatrolEnv"]
