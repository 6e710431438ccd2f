"""Headless pygame for the env tests: the SDL drivers must be chosen before pygame is imported,
and pytest imports this file before the test modules of the folder."""

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
