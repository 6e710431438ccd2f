"""Geometry: polygons with holes, map files, the named map zoo, generators and ray casting."""

from bounce_gym.worlds.world import World  # noqa: I001  (World must load before its users)
from bounce_gym.worlds.grid import parse_ascii, to_ascii, world_from_grid
from bounce_gym.worlds.raycast import Hits

__all__ = ["Hits", "World", "parse_ascii", "to_ascii", "world_from_grid"]
