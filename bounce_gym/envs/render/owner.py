"""What every env that draws keeps of its renderer: closing it and leaving it out of pickles."""

from __future__ import annotations


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
