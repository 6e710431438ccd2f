"""Analytic planners and reference policies for bounce_gym worlds."""
