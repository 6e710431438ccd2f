"""The JAX env benchmark (issues 26, 39) runs with a tiny budget and reports every row."""

from benchmarks import jax_env


def test_jax_env_benchmark_runs(capsys):
    out = jax_env.main(["--steps", "4", "--rounds", "2", "--sizes", "64"])
    text = capsys.readouterr().out
    assert set(out["rates"]) == ({f"{env} {kind} N=64" for env in jax_env.ENVS
                                  for kind in ("JAX", "native")}
                                 | {f"{env} bare N=64" for env in jax_env.CELL_ENVS}
                                 | {f"{env} JAX N=64" for env in jax_env.JAX_ONLY})
    assert set(out["ratios"]) == ({f"{env}: JAX ÷ native, N=64" for env in jax_env.ENVS}
                                  | {f"{env}: {side} ÷ bare lookup, N=64"
                                     for env in jax_env.CELL_ENVS
                                     for side in jax_env.BARE_TARGETS})
    assert all(len(v) == 2 and min(v) > 0 for v in out["rates"].values())
    for row in out["ratios"].values():
        assert 0 < row["low"] <= row["median"] <= row["high"]
    assert "load average" in text and "≥ 10" in text and "XLA thread" in text
