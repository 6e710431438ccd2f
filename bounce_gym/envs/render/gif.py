"""Animated GIFs of rendered episodes (Pillow).

`save_gif` writes a list of RGB frames as a looping GIF, atomically: the file appears complete or
not at all. `record_episode` runs one episode of an ``rgb_array`` env and saves it.

Pillow merges consecutive identical frames into one longer frame (the animation's timing is
unchanged), so a reader may see fewer frames than were written when the picture did not change.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bounce_gym.errors import ConfigError
from bounce_gym.extras import require
from bounce_gym.files import atomic_file


def _check_frames(frames: Sequence[np.ndarray]) -> list[np.ndarray]:
    if isinstance(frames, np.ndarray) and frames.ndim == 4:
        frames = list(frames)
    try:
        frames = list(frames)
    except TypeError as exc:
        raise ConfigError(
            f"frames must be a list of (H, W, 3) uint8 arrays, got {type(frames).__name__}"
        ) from exc
    if not frames:
        raise ConfigError("frames is empty: a GIF needs at least one frame")
    first_shape = None
    for i, frame in enumerate(frames):
        if not isinstance(frame, np.ndarray):
            raise ConfigError(f"frames[{i}] must be a numpy array, got {type(frame).__name__}")
        if frame.dtype != np.uint8:
            raise ConfigError(f"frames[{i}] must have dtype uint8, got {frame.dtype}")
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.shape[0] < 1 or frame.shape[1] < 1:
            raise ConfigError(f"frames[{i}] must have shape (H, W, 3), got {frame.shape}")
        if first_shape is None:
            first_shape = frame.shape
        elif frame.shape != first_shape:
            raise ConfigError(
                f"frames[{i}] has shape {frame.shape} but frames[0] has shape {first_shape}; "
                "all frames must have the same shape"
            )
    return frames


def save_gif(frames: Sequence[np.ndarray], path: str | os.PathLike, fps: float = 10,
             width: int | None = None) -> Path:
    """Write ``frames`` as a GIF that loops forever.

    Args:
        frames: non-empty list of (H, W, 3) ``uint8`` RGB arrays, all the same shape.
        path: output file; its parent directory is created if missing.
        fps: frames per second (> 0). GIF delays are whole centiseconds, so the real rate is
            rounded.
        width: resize frames to this width in pixels (aspect ratio kept); None keeps them.

    Returns:
        The output path.

    Raises:
        ConfigError: no frames, a frame that is not (H, W, 3) uint8, frames of different
            shapes, or a bad ``fps``.

    The GIF is written to a temporary file in the same directory and moved into place with
    `os.replace`, so readers never see a half-written file and a failure leaves nothing behind.
    """
    require("writing a GIF", "PIL")
    from PIL import Image

    frames = _check_frames(frames)
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.number)):
        raise ConfigError(f"fps must be a number > 0, got {fps!r}")
    if not math.isfinite(float(fps)) or fps <= 0:
        raise ConfigError(f"fps must be a finite number > 0, got {fps!r}")
    duration = max(10, round(1000.0 / float(fps) / 10) * 10)  # milliseconds, whole centiseconds

    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    images = [Image.fromarray(np.ascontiguousarray(f)) for f in frames]
    if width is not None:
        if isinstance(width, bool) or not isinstance(width, int | np.integer) or width < 1:
            raise ConfigError(f"width must be a positive integer, got {width!r}")
        height = max(1, round(images[0].height * width / images[0].width))
        images = [im.resize((int(width), height), Image.Resampling.LANCZOS) for im in images]
    # an adaptive palette without dithering: crisp flat colours and a much smaller file
    images = [im.convert("P", palette=Image.Palette.ADAPTIVE, colors=128,
                         dither=Image.Dither.NONE) for im in images]
    with atomic_file(out) as fh:
        images[0].save(fh, format="GIF", save_all=True, append_images=images[1:],
                       duration=duration, loop=0)
    return out


def record_episode(
    env: Any,
    policy: Callable[[Any, dict], Any] | None,
    path: str | os.PathLike,
    max_steps: int = 200,
    seed: int | None = None,
    fps: float | None = 10,
    width: int | None = None,
) -> Path:
    """Run one episode of ``env`` and save its frames as a GIF.

    Args:
        env: a Gymnasium env created with ``render_mode="rgb_array"``. It is not closed.
        policy: ``policy(obs, info) -> action``; None samples ``env.action_space`` (seeded with
            ``seed``, so a seeded recording is reproducible).
        path: output GIF path.
        max_steps: at most this many steps (so at most ``max_steps + 1`` frames, the first one
            right after reset).
        seed: passed to ``env.reset(seed=seed)``.
        fps: frames per second of the GIF; None uses ``env.metadata["render_fps"]`` (or 10).
        width: resize the frames to this width (see `save_gif`).

    Returns:
        The output path.

    Raises:
        ConfigError: the env does not render ``rgb_array`` frames, or ``max_steps < 0``.
    """
    mode = getattr(env, "render_mode", None)
    if mode != "rgb_array":
        raise ConfigError(
            f'record_episode needs an env made with render_mode="rgb_array", got {mode!r}'
        )
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 0:
        raise ConfigError(f"max_steps must be an integer >= 0, got {max_steps!r}")
    if fps is None:
        fps = (getattr(env, "metadata", None) or {}).get("render_fps") or 10

    obs, info = env.reset(seed=seed)
    if policy is None:
        env.action_space.seed(seed)

    def grab() -> np.ndarray:
        frame = env.render()
        if not isinstance(frame, np.ndarray):
            raise ConfigError(
                f"env.render() returned {type(frame).__name__}, expected an (H, W, 3) array"
            )
        return frame

    frames = [grab()]
    for _ in range(int(max_steps)):
        action = env.action_space.sample() if policy is None else policy(obs, info)
        obs, _reward, terminated, truncated, info = env.step(action)
        frames.append(grab())
        if terminated or truncated:
            break
    return save_gif(frames, path, fps=fps, width=width)
