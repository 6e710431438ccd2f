"""Helpers every figure uses: a headless matplotlib, the world outline, atomic PNG files."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from bounce_gym.files import atomic_write


def pyplot():
    """matplotlib.pyplot on the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_world(ax, world) -> None:
    """The world's boundary rings, equal aspect, no axes."""
    for ring in world.rings:
        closed = np.vstack([ring, ring[:1]])
        ax.plot(closed[:, 0], closed[:, 1], color="#223", lw=1.5)
    ax.set_aspect("equal")
    ax.axis("off")


def save_figure(fig, path: Path | str) -> Path:
    """Save a matplotlib figure as a PNG atomically and close it."""
    plt = pyplot()
    path = Path(path)
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(path, buf.getvalue())
    return path
