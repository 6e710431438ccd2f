"""Ocean currents for drifters: layered flow fields (`FlowField`), CF NetCDF files
(`load_flow`, `save_flow`) and a seeded zoo of synthetic fields (`get_flow`, `flow_names`).

This package sits at the bottom of the layers beside `bounce_gym.worlds`: it imports nothing
of bounce_gym but the errors, the shared checks and the file writer.
"""

from bounce_gym.flows.field import CRS, METRES_PER_DEGREE, FlowField
from bounce_gym.flows.netcdf import flow_from_dataset, flow_to_dataset, load_flow, save_flow
from bounce_gym.flows.zoo import ekman_layers, flow_names, get_flow, two_sink_land

__all__ = [
    "CRS",
    "METRES_PER_DEGREE",
    "FlowField",
    "ekman_layers",
    "flow_from_dataset",
    "flow_to_dataset",
    "get_flow",
    "load_flow",
    "flow_names",
    "save_flow",
    "two_sink_land",
]
