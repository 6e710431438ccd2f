"""Experiments: configurations, the episode runner, per-family metrics and plots, reports."""
