"""The sweep command before Ray: listing the runs, and refusing a results directory that holds
another sweep's runs."""

from __future__ import annotations

import yaml

from sgim_nodes.sweep import driver, results
from sgim_nodes.sweep.sweep_file import load
from tests.sweep.test_results import make_run, unlike_fingerprint


def _sweep(tmp_path):
    path = tmp_path / "two.yaml"
    path.write_text(yaml.safe_dump({"learner": "sgim-d", "movements": 100, "seeds": [2],
                                    "demonstration_period": [50, 150],
                                    "param": {"imitation_count": 3}}))
    return path, tmp_path / "runs"


def test_list_shows_every_run_its_state_and_its_command(tmp_path, capsys):
    path, runs = _sweep(tmp_path)
    done, todo = load(path, runs).runs
    make_run(runs / done.name)  # SPEC of test_results: the P50 run, finished
    assert driver.main([str(path), "--runs-dir", str(runs), "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split("\t")[:2] for line in lines] == [[done.name, "finished"],
                                                         [todo.name, "absent"]]
    assert lines[1].split("\t")[2] == " ".join(todo.argv())
    assert not (runs / results.STATUS_FILE).exists(), "--list writes nothing"


def test_a_finished_run_of_other_settings_stops_the_sweep_untouched(tmp_path, capsys):
    path, runs = _sweep(tmp_path)
    done = load(path, runs).runs[0]
    make_run(runs / done.name, imitation_count=5)
    assert driver.main([str(path), "--runs-dir", str(runs)]) == 2
    assert "imitation_count: 5 recorded, 3 asked" in capsys.readouterr().err
    assert sorted(p.name for p in runs.iterdir()) == [done.name]


def test_a_bad_sweep_file_is_refused_before_ray(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text("learner: sgim-d\nparam: {goal_budgte: 3}\n")
    assert driver.main([str(path)]) == 2
    assert "did you mean 'goal_budget'" in capsys.readouterr().err


def test_resume_makes_a_run_of_another_learner_again_and_keeps_the_old_one(
        tmp_path, capsys, monkeypatch):
    path, runs = _sweep(tmp_path)
    done, todo = load(path, runs).runs
    make_run(runs / done.name, fingerprint=unlike_fingerprint(code="0" * 16))
    submitted = []
    monkeypatch.setattr(driver, "run_sweep",
                        lambda sweep, args, todo, states: submitted.extend(todo) or 0)
    assert driver.main([str(path), "--runs-dir", str(runs)]) == 0
    assert [s.name for s in submitted] == [done.name, todo.name]
    err = capsys.readouterr().err
    assert f"{done.name}: its learner differs from this checkout's: code; made again" in err
    kept = runs / results.UNLIKE_DIR / f"{done.name}.1"
    assert (kept / "metadata.yaml").is_file() and not (runs / done.name).exists()


def test_keep_unlike_keeps_the_run_as_finished(tmp_path, capsys, monkeypatch):
    path, runs = _sweep(tmp_path)
    done, todo = load(path, runs).runs
    make_run(runs / done.name, fingerprint=unlike_fingerprint(numpy="1.0"))
    submitted = []
    monkeypatch.setattr(driver, "run_sweep",
                        lambda sweep, args, todo, states: submitted.extend(todo) or 0)
    assert driver.main([str(path), "--runs-dir", str(runs), "--keep-unlike"]) == 0
    assert [s.name for s in submitted] == [todo.name]
    assert "numpy; kept (--keep-unlike)" in capsys.readouterr().err
    assert (runs / done.name / "metadata.yaml").is_file()
