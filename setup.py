"""Package list for setuptools (the rest of the metadata is in pyproject.toml): the packages
found in the source tree, plus ``bounce_gym_experiments.configs`` — the top-level ``configs/`` folder,
installed inside the package so that an installed ``bounce-gym evaluate`` finds its default
configuration."""

from setuptools import find_namespace_packages, setup

setup(packages=[*find_namespace_packages(include=["bounce_gym*", "baselines*", "bounce_gym_experiments*"]),
                "bounce_gym_experiments.configs"])
