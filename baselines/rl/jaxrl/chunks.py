"""A chunk of a learner's iterations as one jitted ``lax.scan``; the iterations past the run's
last are skipped (``lax.cond``), so every chunk has the same length and compiles once."""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp


def chunk_function(iterate: Callable, iterations: int, length: int) -> Callable:
    """``state -> (state, records)``: ``length`` calls of ``iterate(state) -> (state,
    records)`` with a counter ``state.iteration``; once it reaches ``iterations`` the state is
    kept and the records are zeros (no episode ended)."""

    def step(state, _):
        shapes = jax.eval_shape(iterate, state)[1]

        def skip(s):
            return s, jax.tree.map(lambda x: jnp.zeros(x.shape, x.dtype), shapes)

        return jax.lax.cond(state.iteration < iterations, iterate, skip, state)

    return jax.jit(lambda state: jax.lax.scan(step, state, None, length))
