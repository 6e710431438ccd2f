"""The provenance record (`bounce_gym.provenance`): the processor's name read from /proc/cpuinfo
(bounded), and what a shipped model file says about the machine that trained it."""

from pathlib import Path

import pytest

from baselines.rl.model_files import read_model
from bounce_gym.provenance import PACKAGES, cpu_model, provenance

AGENTS = Path(__file__).parents[1] / "baselines" / "agents"


@pytest.mark.parametrize(("text", "name"), [
    ("processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel name\t: AMD EPYC 7B13\nflags\t: fma\n",
     "AMD EPYC 7B13"),
    ("processor\t: 0\nBogoMIPS\t: 50.00\nCPU part\t: 0xd0c\n\nHardware\t: BCM2835\n", "BCM2835"),
    ("model name\t: first\nmodel name\t: second\n", "first"),
])
def test_the_processor_is_named_from_cpuinfo(tmp_path, text, name):
    (tmp_path / "cpuinfo").write_text(text)
    assert cpu_model(tmp_path / "cpuinfo") == name


def test_without_cpuinfo_the_processor_is_what_platform_says(tmp_path, monkeypatch):
    monkeypatch.setattr("bounce_gym.provenance.platform.processor", lambda: "arm")
    assert cpu_model(tmp_path / "absent") == "arm"
    (tmp_path / "empty").write_text("model name\t:\n" + "x" * 100_000)  # read only in part
    monkeypatch.setattr("bounce_gym.provenance.platform.processor", lambda: "")
    assert cpu_model(tmp_path / "empty") is None


def test_the_record_names_versions_machine_and_commit():
    made = provenance()
    assert set(made) == {"packages", "git", "python", "platform", "machine", "cpu"}
    assert set(made["packages"]) == set(PACKAGES) >= {"numpy", "torch", "jax", "jaxlib", "optax"}
    assert made["machine"] and made["packages"]["numpy"]


def test_shipped_sb3_agents_show_what_sb3_recorded_and_jax_agents_nothing():
    sb3 = read_model(AGENTS / "navigation-lab-v1" / "dqn_seed0.zip").trained_with()
    assert sb3 is not None
    assert {"OS", "Python", "Stable-Baselines3", "PyTorch", "Numpy", "Gymnasium"} <= set(
        sb3["sb3_system_info"])
    for algo in ("jax_ppo", "jax_dqn"):  # shipped before the record was written
        assert read_model(AGENTS / "navigation-lab-v1" / f"{algo}_seed0.zip").trained_with() is None
