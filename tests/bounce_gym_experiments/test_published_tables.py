"""Result tables in README.md and docs/ are generated from the leaderboard files they cite
(issue 34): a committed table that differs from its file fails here."""

import shutil
from pathlib import Path

import pytest

from bounce_gym.errors import ConfigError
from bounce_gym_experiments import published
from bounce_gym_experiments.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_every_committed_result_table_equals_the_file_it_cites():
    assert published.stale(ROOT) == []


def test_the_readme_cites_the_benchmark_verdicts():
    text = (ROOT / "README.md").read_text()
    assert "<!-- results: docs/results/benchmark/verdicts.csv -->" in text
    assert (ROOT / "docs/results/benchmark/verdicts.csv").is_file()


VERDICTS = ("experiment,score,direction,planner,rl,random,rl_vs_planner,rl_vs_random,"
            "planner_vs_random,discriminates\n"
            'a,success,higher,"p: 1.000 [1.000, 1.000] n=200",-,"r: 0.300 [0.2, 0.4] n=200",-,-,'
            '"P=0.85 [0.82, 0.88]: p",yes\n'
            'b,success,higher,p: 1.000,-,r: 1.000,-,-,"P=0.50 [0.50, 0.50]: no difference",no\n')
LEADERBOARD = ("experiment,difficulty,env,policy,episodes,seeds,score,success,success_lo,"
               "success_hi,success_n,ticks,ticks_lo,ticks_hi,ticks_n\n"
               "a,easy,x,p,200,,success,1.0,1.0,1.0,200,20.5,19.0,22.0,200\n"
               "a,easy,x,rl q,1000,2,success,0.9,0.8,0.95,1000,,,,\n")


@pytest.fixture()
def repo(tmp_path):
    (tmp_path / "docs/results/b").mkdir(parents=True)
    (tmp_path / "docs/results/b/verdicts.csv").write_text(VERDICTS)
    (tmp_path / "docs/results/b/leaderboard.csv").write_text(LEADERBOARD)
    (tmp_path / "README.md").write_text(
        "intro\n<!-- results: docs/results/b/verdicts.csv -->\nold\n<!-- end results -->\nend\n")
    (tmp_path / "docs/page.md").write_text(
        "<!-- results: docs/results/b/leaderboard.csv columns=ticks -->\n<!-- end results -->\n")
    return tmp_path


def test_stale_tables_are_listed_and_rewritten(repo):
    assert published.stale(repo) == [
        "README.md: docs/results/b/verdicts.csv",
        "docs/page.md: docs/results/b/leaderboard.csv columns=ticks"]
    assert sorted(p.name for p in published.rewrite(repo)) == ["README.md", "page.md"]
    assert published.stale(repo) == []
    readme = (repo / "README.md").read_text()
    assert "| a | success (higher is better) | p: 1.000 [1.000, 1.000] n=200 |" in readme
    assert "| b |" not in readme and "on the score: b." in readme
    assert readme.startswith("intro\n") and readme.endswith("<!-- end results -->\nend\n")
    page = (repo / "docs/page.md").read_text()
    assert "| p | 1.000 [1.000, 1.000] n=200 | 20.5 [19.0, 22.0] n=200 |" in page
    assert "| rl q [2 seeds < 5] | 0.900 [0.800, 0.950] n=1000 | - |" in page
    # a table edited by hand is stale again
    (repo / "README.md").write_text(readme.replace("n=200 |", "n=199 |", 1))
    assert published.stale(repo) == ["README.md: docs/results/b/verdicts.csv"]


def test_a_block_cites_only_leaderboard_files_inside_the_repository(repo):
    (repo / "docs/page.md").write_text("<!-- results: ../../etc/passwd -->\n<!-- end results -->\n")
    with pytest.raises(ConfigError, match="inside the repository"):
        published.stale(repo)


def test_the_tables_command_publishes_a_run_and_checks(repo, monkeypatch, capsys):
    run = repo / "runs/x"
    run.mkdir(parents=True)
    for name in ("leaderboard.md", "leaderboard.csv", "verdicts.csv"):
        shutil.copyfile(repo / "docs/results/b" / name if name != "leaderboard.md"
                        else repo / "README.md", run / name)
    monkeypatch.chdir(repo)
    assert main(["tables"]) == 1 and "stale: README.md" in capsys.readouterr().out
    assert main(["tables", "--from", "runs/x", "--into", "docs/results/b", "--write"]) == 0
    assert (repo / "docs/results/b/leaderboard.md").read_text() == (
        repo / "runs/x/leaderboard.md").read_text()
    assert main(["tables"]) == 0
    assert main(["tables", "--from", "runs/nothing"]) == 2
    assert "has no leaderboard.md" in capsys.readouterr().err
