"""The reset draws of the JAX envs are uniform (chi-square) and in range."""

import jax
import jax.numpy as jnp
import numpy as np
from scipy import stats

from bounce_gym.jax import draws


def test_indices_are_uniform_and_in_range():
    keys = jax.random.split(jax.random.PRNGKey(0), 200_000)
    u = jax.vmap(lambda k: draws.uniforms(k, 2))(keys)
    i = np.asarray(draws.index(u[:, 0], 48))
    assert i.min() == 0 and i.max() == 47
    assert stats.chisquare(np.bincount(i, minlength=48)).pvalue > 1e-3
    assert int(draws.index(jnp.float32(np.nextafter(np.float32(1), np.float32(0))), 7)) == 6
