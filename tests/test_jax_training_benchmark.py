"""The end-to-end rows of the JAX training benchmark (issue 39) run, with every training capped
at a few thousand steps (``BOUNCE_GYM_MAX_TIMESTEPS``), and print each time and ratio."""

import pytest

from benchmarks import jax_training

pytest.importorskip("jax")
pytest.importorskip("stable_baselines3")


@pytest.mark.slow
def test_end_to_end_rows_run(capsys, monkeypatch):
    monkeypatch.setenv("BOUNCE_GYM_MAX_TIMESTEPS", "2048")
    jax_training.end_to_end_rows(1)
    text = capsys.readouterr().out
    for row in ("ppo ", "jax_ppo cold", "jax_ppo warm", "ppo ÷ jax_ppo warm"):
        assert row in text, row
    assert "load" in text and "target ≥ 20" in text
