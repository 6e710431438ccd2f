"""Monitor files and learning curves: SB3's format read back, a resumed run's file cut to its
checkpoint, per-seed moving means, the across-seed mean with its 95% interval, and the
``bounce-gym curves`` command."""

import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

pytest.importorskip("stable_baselines3")

from baselines.rl.curves import learning_curves, smoothed  # noqa: E402
from baselines.rl.monitor import open_monitor_file, read_monitor  # noqa: E402
from bounce_gym.errors import ConfigError  # noqa: E402
from bounce_gym_experiments.cli import main  # noqa: E402


def _monitor(path: Path, rows: list[tuple], partial: str = "") -> Path:
    lines = [f"#{json.dumps({'t_start': 0.0, 'env_id': 'x'})}", "r,l,t,is_success"]
    lines += [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n" + partial)
    return path


def test_smoothed_is_the_mean_of_the_last_window_values():
    assert smoothed(np.array([1.0, 3.0, 5.0, 7.0]), 2).tolist() == [1.0, 2.0, 4.0, 6.0]
    assert smoothed(np.array([2.0, 4.0]), 100).tolist() == [2.0, 3.0]


def test_monitor_files_are_read_as_sb3_writes_them(tmp_path):
    from stable_baselines3.common.monitor import load_results

    rows = [(-5.0, 10, 0.1, True), (-7.5, 20, 0.2, False)]
    path = _monitor(tmp_path / "ppo_seed0.monitor.csv", rows)
    theirs = load_results(str(tmp_path))
    ours = read_monitor(path)
    assert ours["r"].tolist() == theirs["r"].tolist() == [-5.0, -7.5]
    assert ours["l"].tolist() == theirs["l"].tolist() and ours["steps"].tolist() == [10, 30]
    assert ours["is_success"].tolist() == [1.0, 0.0]
    _monitor(path, rows, partial="-1.0,3")  # a crash mid-line: the partial row is left out
    assert read_monitor(path)["r"].tolist() == [-5.0, -7.5]


def test_a_resumed_run_keeps_exactly_the_episodes_before_its_checkpoint(tmp_path):
    path = _monitor(tmp_path / "m.monitor.csv", [(-1.0, 1, 0.1, True)] * 5, partial="-2.0,")
    writer = open_monitor_file(path, 0.0, "x", ("is_success",), keep_rows=3)
    writer.write_row({"r": -9.0, "l": 4, "t": 1.0, "is_success": False})
    writer.close()
    assert read_monitor(path)["r"].tolist() == [-1.0, -1.0, -1.0, -9.0]
    with pytest.raises(ConfigError, match=r"holds 4 episodes, but the checkpoint was taken "
                                          r"after 6"):
        open_monitor_file(path, 0.0, "x", ("is_success",), keep_rows=6)


def test_the_monitor_file_is_written_as_sb3_writes_it(tmp_path):
    from stable_baselines3.common.monitor import ResultsWriter

    theirs = ResultsWriter(str(tmp_path / "a.monitor.csv"), header={"t_start": 1.5, "env_id": "x"},
                           extra_keys=("is_success",))
    ours = open_monitor_file(tmp_path / "b.monitor.csv", 1.5, "x", ("is_success",))
    for writer in (theirs, ours):
        writer.write_row({"r": -1.0, "l": 7, "t": 0.25, "is_success": True})
        writer.close()
    assert (tmp_path / "a.monitor.csv").read_bytes() == (tmp_path / "b.monitor.csv").read_bytes()


def test_a_monitor_file_planted_as_a_link_is_never_written_through(tmp_path):
    """A new file replaces the link (its target untouched); a resumed run, which would read and
    append to the file, refuses it."""
    victim = _monitor(tmp_path / "victim.csv", [(-1.0, 1, 0.1, True)] * 4)
    before = victim.read_bytes()
    link = tmp_path / "ppo_seed0.monitor.csv"
    link.symlink_to(victim)
    with pytest.raises(ConfigError, match="ppo_seed0.monitor.csv: is a symbolic link"):
        open_monitor_file(link, 0.0, "x", ("is_success",), keep_rows=2)
    assert victim.read_bytes() == before and link.is_symlink()
    writer = open_monitor_file(link, 0.0, "x", ("is_success",))
    writer.write_row({"r": 2.0, "l": 3, "t": 0.5, "is_success": False})
    writer.close()
    assert victim.read_bytes() == before and not link.is_symlink()
    assert read_monitor(link)["r"].tolist() == [2.0]


def test_curves_per_seed_and_across_seeds(tmp_path):
    for seed, value in ((0, 1.0), (10, 3.0)):
        _monitor(tmp_path / f"ppo_seed{seed}.monitor.csv",
                 [(value, 10, 0.1, value > 2)] * 20)
    _monitor(tmp_path / "dqn_seed0.monitor.csv", [(0.0, 5, 0.1, False)] * 3)
    (dqn, ppo) = learning_curves(tmp_path, window=5)
    assert (dqn.name, ppo.name, list(ppo.seeds)) == ("dqn", "ppo", [0, 10])
    assert ppo.final(10) == {"episodes": 20, "env_steps": 200, "return": 3.0, "success": 1.0}
    steps, mean, low, high = ppo.across_seeds("return")
    half = stats.t.ppf(0.975, 1) * np.std([1.0, 3.0], ddof=1) / np.sqrt(2)
    assert steps[-1] == 200 and np.isnan(mean[0])  # before the first episode ends
    assert mean[-1] == pytest.approx(2.0) and high[-1] - mean[-1] == pytest.approx(half)
    assert np.isnan(dqn.across_seeds("return")[2]).all()  # one seed: no interval


def test_the_curves_command_draws_a_models_folder(tmp_path, capsys):
    folder = tmp_path / "nav"
    folder.mkdir()
    assert main(["curves", str(folder)]) == 2
    assert "holds no monitor file with a finished episode" in capsys.readouterr().err
    for seed in (0, 1, 2):
        _monitor(folder / f"ppo_seed{seed}.monitor.csv",
                 [(-float(seed + k), 10, 0.1, k % 2 == 0) for k in range(30)])
    assert main(["curves", str(folder), "--window", "10"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("ppo: 3 seeds, at 300 env steps: return ")
    assert (folder / "learning_curves.png").stat().st_size > 0
    rows = (folder / "learning_curves.csv").read_text().splitlines()
    assert rows[0] == "run,seed,episodes,env_steps,return,success" and len(rows) == 4


def test_a_monitor_file_holds_at_most_the_row_cap(tmp_path, monkeypatch):
    from baselines.rl import monitor

    path = _monitor(tmp_path / "ppo_seed0.monitor.csv", [(-1.0, 10, 0.1, True)] * 11)
    monkeypatch.setattr(monitor, "MAX_MONITOR_ROWS", 11)
    assert len(read_monitor(path)["r"]) == 11
    monkeypatch.setattr(monitor, "MAX_MONITOR_ROWS", 10)
    with pytest.raises(ConfigError, match="holds more than the 10 episodes a monitor file may"):
        read_monitor(path)


def test_a_monitor_file_is_read_as_a_stream(tmp_path):
    """Reading holds the columns (float64) and a chunk of lines at a time, never the whole
    text or a Python object per value: a file of 300,000 episodes (about 8 MB of text) takes at
    most twice its arrays plus 24 MB at its peak (reading it whole took 106 MiB)."""
    import tracemalloc

    rows = 300_000
    path = tmp_path / "ppo_seed0.monitor.csv"
    path.write_text(f"#{json.dumps({'t_start': 0.0, 'env_id': 'x'})}\nr,l,t,is_success\n"
                    + "".join(f"{-(k % 97) / 97:.6f},{k % 200 + 1},{k / 100:.2f},{k % 3 == 0}\n"
                              for k in range(rows)))
    tracemalloc.start()
    try:
        columns = read_monitor(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    arrays = sum(column.nbytes for column in columns.values())
    assert len(columns["r"]) == rows and columns["steps"][-1] == sum(k % 200 + 1
                                                                     for k in range(rows))
    assert columns["is_success"].sum() == len(range(0, rows, 3))
    assert peak < 2 * arrays + (24 << 20), f"{peak >> 20} MiB at the peak"


def test_a_monitor_file_with_windows_line_ends_and_blank_lines(tmp_path):
    path = tmp_path / "ppo_seed0.monitor.csv"
    path.write_bytes(b'#{"t_start": 0}\r\nr,l,t,is_success\r\n-1.5,3,0.1,True\r\n\r\n'
                     b"2,4,0.2,0.0\r\n-3,5,0.3,Fal")
    columns = read_monitor(path)
    assert columns["r"].tolist() == [-1.5, 2.0] and columns["steps"].tolist() == [3, 7]
    assert columns["is_success"].tolist() == [1.0, 0.0]


def test_a_seeds_line_is_drawn_through_at_most_its_share_of_points(tmp_path):
    from bounce_gym_experiments.plots import learning_curves as plots

    assert plots._spaced(3, 10).tolist() == [0, 1, 2]
    spaced = plots._spaced(1_000_001, plots.SEED_POINTS)
    assert len(spaced) == plots.SEED_POINTS and spaced[0] == 0 and spaced[-1] == 1_000_000
