"""Reinforcement-learning baselines: Stable-Baselines3 training and a PettingZoo-to-VecEnv
adapter for one policy shared by every robot."""
