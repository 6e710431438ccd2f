"""Geometry: polygons with holes, map files, the named map zoo, generators and ray casting."""

from bounce_gym.worlds.world import World  # noqa: I001  (World must load before its users)
from bounce_gym.worlds.grid import parse_ascii, to_ascii, world_from_grid
from bounce_gym.worlds.raycast import Hits
from bounce_gym.worlds.io import from_dict, load, save, to_dict
from bounce_gym.worlds.zoo import describe, get, names
from bounce_gym.worlds.generators import random_grid, random_room_tree, random_star_polygon

__all__ = [
    "Hits",
    "World",
    "describe",
    "from_dict",
    "get",
    "load",
    "names",
    "parse_ascii",
    "random_grid",
    "random_room_tree",
    "random_star_polygon",
    "save",
    "to_ascii",
    "to_dict",
    "world_from_grid",
]
