"""Reinforcement-learning baselines: Stable-Baselines3 training and a PettingZoo-to-VecEnv
adapter for one policy shared by every robot."""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
