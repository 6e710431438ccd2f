"""What every env that draws shares: its render modes, and keeping its renderer (closing it,
leaving it out of pickles)."""

from __future__ import annotations

from bounce_gym.errors import ConfigError

#: The render modes of every env that draws.
RENDER_MODES = ["human", "rgb_array"]


def checked_render_mode(render_mode: object) -> str | None:
    """``render_mode`` if it is None or one of `RENDER_MODES`."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ConfigError(f"render_mode: expected None or one of {RENDER_MODES}, "
                          f"got {render_mode!r}")
    return render_mode


class RendererOwner:
    """Mixin for envs holding a lazily built renderer in ``self._renderer``."""

    _renderer = None

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_renderer"] = None  # pygame objects are rebuilt on the next render()
        return state
