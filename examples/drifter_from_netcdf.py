"""A drifter in currents read from a NetCDF file that you write yourself with xarray.

The file follows the CF conventions `bounce_gym.flows.load_flow` reads: ``u`` and ``v`` with
the standard names ``eastward_sea_water_velocity`` / ``northward_sea_water_velocity`` in
``m s-1`` on ``(depth, y, x)``, NaN on land, ``x``/``y`` in metres with their CF axes and
``depth`` in metres, ``positive: down``. The channel here has three layers: the surface
current runs east, the middle one west and the deep one north, with land on the rim and a
small island. ``Drifter-v0`` takes the file as ``flow=path``; the goal is a 3 x 3 block of
surface cells in the north-west. `baselines.drifters.ValueIterationPolicy` (Alam 2018,
Alg. 5.5) plans on the env's cell model, predicts its success from each start, and then rises,
sinks or drifts on held-out episode seeds (from 10,000); the measured success rate is printed
with its 95 % Wilson interval next to the mean prediction.

Run with ``python examples/drifter_from_netcdf.py`` (``--episodes``, ``--out FOLDER``; the flow
is ``FOLDER/channel.nc``, by default in a fresh temporary folder that is printed at the end).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from bounce_gym.extras import exit_unless_installed

# the extra this example needs, checked before anything imports it
exit_unless_installed("examples/drifter_from_netcdf.py", "xarray", "netCDF4")

import gymnasium as gym
import numpy as np
import xarray as xr

import bounce_gym  # noqa: F401  (registers the environments)
from baselines.drifters import ValueIterationPolicy
from baselines.seeds import EVALUATION_SEEDS_START
from bounce_gym.flows import load_flow
from bounce_gym_experiments.stats import wilson_interval

ROWS, COLUMNS, CELL = 10, 14, 1000.0  # cells, metres
DEPTHS = np.array([0.0, 10.0, 20.0])  # metres, positive down
#: (u, v) of each layer in m/s: east on top, west in the middle, north at the bottom
LAYER_CURRENTS = [(0.3, 0.05), (-0.3, 0.05), (0.0, 0.3)]
GOAL = {"cell": (0, 7, 2), "halo": 1}  # (layer, row, column): 3 x 3 surface cells


def write_channel(path: Path) -> Path:
    """Write the three-layer channel as a CF NetCDF file at ``path``."""
    land = np.zeros((ROWS, COLUMNS), bool)
    land[[0, -1], :] = land[:, [0, -1]] = True  # the rim
    land[4:6, 6:8] = True                       # an island
    u = np.empty((len(DEPTHS), ROWS, COLUMNS))
    v = np.empty_like(u)
    for layer, (east, north) in enumerate(LAYER_CURRENTS):
        u[layer], v[layer] = east, north
    u[:, land] = v[:, land] = np.nan
    velocity = {"units": "m s-1"}
    dims = ("depth", "y", "x")
    ds = xr.Dataset(
        {"u": (dims, u, {**velocity, "standard_name": "eastward_sea_water_velocity"}),
         "v": (dims, v, {**velocity, "standard_name": "northward_sea_water_velocity"})},
        coords={
            "depth": ("depth", DEPTHS, {"units": "m", "positive": "down", "axis": "Z"}),
            "y": ("y", (np.arange(ROWS) + 0.5) * CELL,
                  {"units": "m", "standard_name": "projection_y_coordinate", "axis": "Y"}),
            "x": ("x", (np.arange(COLUMNS) + 0.5) * CELL,
                  {"units": "m", "standard_name": "projection_x_coordinate", "axis": "X"}),
        },
        attrs={"Conventions": "CF-1.8", "title": "three-layer channel"},
    )
    ds.to_netcdf(path, engine="netcdf4")
    return path


def run(path: Path, episodes: int) -> dict:
    """Plan and play ``episodes`` held-out episodes on the flow at ``path``."""
    env = gym.make("bounce_gym/Drifter-v0", flow=str(path), goal=GOAL)
    planner = ValueIterationPolicy()
    horizon = env.spec.max_episode_steps
    predicted, reached, steps = [], 0, []
    for seed in range(EVALUATION_SEEDS_START, EVALUATION_SEEDS_START + episodes):
        obs, info = env.reset(seed=seed)
        planner.reset(env)
        predicted.append(planner.predicted_success(info["state"], horizon=horizon))
        start = info["cell"]
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(planner.act(obs, info))
            done = terminated or truncated
        reached += bool(info["is_success"])
        steps.append(info["steps"])
        if seed == EVALUATION_SEEDS_START:
            print(f"first episode: start {start}, predicted {predicted[-1]:.3f}, "
                  f"goal reached {info['is_success']} after {info['steps']} steps "
                  f"at {info['cell']}")
    env.close()
    return {"reached": reached, "predicted": float(np.mean(predicted)), "steps": steps}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100, help="held-out episodes")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for the NetCDF file (default: a fresh temporary folder)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="drifter_netcdf_"))
    out.mkdir(parents=True, exist_ok=True)

    path = write_channel(out / "channel.nc")
    print(load_flow(path))  # what the package reads from the file
    result = run(path, args.episodes)
    low, high = wilson_interval(result["reached"], args.episodes)
    print(f"value iteration (Alg. 5.5), goal {GOAL}: success "
          f"{result['reached'] / args.episodes:.3f} [{low:.3f}, {high:.3f}] n={args.episodes}; "
          f"model's mean prediction {result['predicted']:.3f}; median episode length "
          f"{np.median(result['steps']):.0f} steps")
    print(f"flow file written to {path}")


if __name__ == "__main__":
    main()
