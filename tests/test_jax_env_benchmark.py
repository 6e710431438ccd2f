"""The JAX env benchmark (issues 26, 39) runs with a tiny budget and reports every row."""

from benchmarks import jax_env


def test_jax_env_benchmark_runs(capsys):
    out = jax_env.main(["--steps", "4", "--rounds", "2", "--sizes", "64"])
    text = capsys.readouterr().out
    jax_kinds = ("JAX", "JAX rbg")
    assert set(out["rates"]) == ({f"{env} {kind} N=64" for env in jax_env.ENVS
                                  for kind in (*jax_kinds, "native")}
                                 | {f"{env} {kind} N=64" for env in jax_env.CELL_ENVS
                                    for kind in ("bare", "API floor")}
                                 | {f"{env} {kind} N=64" for env in jax_env.JAX_ONLY
                                    for kind in jax_kinds})
    assert set(out["ratios"]) == ({f"{env}: {kind} ÷ native, N=64" for env in jax_env.ENVS
                                   for kind in jax_kinds}
                                  | {f"{env}: {side} ÷ bare lookup, N=64"
                                     for env in jax_env.CELL_ENVS
                                     for side in jax_env.BARE_SIDES}
                                  | {f"{env}: native ÷ API floor, N=64"
                                     for env in jax_env.CELL_ENVS})
    assert all(len(v) == 2 and min(v) > 0 for v in out["rates"].values())
    for row in out["ratios"].values():
        assert 0 < row["low"] <= row["median"] <= row["high"]
    assert "load average" in text and "≥ 10" in text and "XLA thread" in text
