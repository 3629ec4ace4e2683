"""The sweep file: expansion, names, what reaches run_experiment, and clear refusals."""

from __future__ import annotations

import re

import pytest
import yaml

from sgim_nodes.graph import batch, experiment_options
from sgim_nodes.graph.description import check
from sgim_nodes.graph.overrides import parse_assignments
from sgim_nodes.sweep import sweep_file
from sgim_nodes.sweep.sweep_file import SweepFileError, expand, load
from tests.conftest import REPO

SWEEPS = REPO / "sgim_nodes" / "config" / "sweeps"


def _names(document: dict) -> list[str]:
    return [spec.name for spec in expand(document)]


def test_defaults_are_run_experiments_own():
    args = experiment_options.parse_args(["sgim-d"])
    expected = {"demonstration_period": args.demonstration_period, "movements": args.movements,
                "eval_every": args.eval_every, "teacher": args.teacher, "storage": args.storage}
    assert expected == sweep_file.DEFAULTS


def test_blocks_are_cartesian_products_and_their_union():
    runs = expand({"movements": 100, "seeds": 2, "grid": [
        {"learner": ["saggriac", "demo-only"]},
        {"learner": "sgim-d", "demonstration_period": [50, 150],
         "param": {"imitation_count": [3, 5]}}]})
    # per seed: 2 + 2 x 2 runs; seed-major so that a sweep cut short covers every setting
    assert len(runs) == 12
    assert [r.seed for r in runs] == [0] * 6 + [1] * 6
    assert {r.name for r in runs if r.seed == 0} == {
        "saggriac-seed0", "demo-only-seed0", "sgim-d-P50-imitation_count=3-seed0",
        "sgim-d-P50-seed0", "sgim-d-imitation_count=3-seed0", "sgim-d-seed0"}


def test_period_maps_to_run_experiments_option_and_params_pass_through():
    [run] = expand({"learner": "sgim-d", "demonstration_period": 50, "movements": 100, "param": {
        "inverse_model": "nearest", "explore_gain": 2.5, "wait_for_evaluation": False,
        "outcome_noise": 1e-5, "imitation_count": 3, "competence_reference": "fixed"}})
    argv = run.argv()
    assert argv[:2] == ["sgim-d", "--seed"]
    assert argv[argv.index("--demonstration-period") + 1] == "50"
    given = [argv[i + 1] for i, a in enumerate(argv) if a == "--param"]
    assert given == ["competence_reference=fixed", "explore_gain=2.5", "imitation_count=3",
                     "inverse_model=nearest", "outcome_noise=1.0e-05",
                     "wait_for_evaluation=false"]
    # run_experiment reads each value back with YAML: the very values of the file, which are
    # what its metadata.yaml will record
    parsed = experiment_options.parse_args(argv)
    assert parsed.demonstration_period == 50
    assigned, _ = parse_assignments(parsed.param)
    assert check(assigned) == {"competence_reference": "fixed", "explore_gain": 2.5,
                               "imitation_count": 3, "inverse_model": "nearest",
                               "outcome_noise": 1e-5, "wait_for_evaluation": False}
    expected = run.expected_parameters()
    assert expected["demonstration_period"] == 50 and expected["teacher"] == "automatic"
    assert expected["wait_for_evaluation"] is False and expected["outcome_noise"] == 1e-5


def test_a_learner_without_teacher_ignores_period_and_teacher():
    runs = expand({"learner": ["sgim-d", "saggriac"], "demonstration_period": [50, 500],
                   "param": {"explore_gain": 2}})
    assert sorted(r.name for r in runs) == [
        "saggriac-explore_gain=2-seed0", "sgim-d-P50-explore_gain=2-seed0",
        "sgim-d-P500-explore_gain=2-seed0"]
    saggriac = next(r for r in runs if r.learner == "saggriac")
    assert "--demonstration-period" not in saggriac.argv() and "--teacher" not in saggriac.argv()
    assert saggriac.argv()[-1] == "explore_gain=2"
    # an integer given to a float parameter is recorded as the float the node reads
    assert saggriac.expected_parameters()["explore_gain"] == 2.0
    assert saggriac.expected_parameters()["teacher"] == "none"


def test_social_modes_are_swept_for_the_learners_with_a_teacher_only():
    runs = expand({"learner": ["sgim-d", "saggriac"], "param": {
        "timing": ["period", "on-request"],
        "demonstration_content": ["means-and-goal", "goal-only"],
        "teacher_choice": "nearest-unreached"}})
    assert sorted(r.name for r in runs) == [
        "saggriac-seed0",  # once: it has no teacher, and none of these reach it
        "sgim-d-demonstration_content=goal-only-teacher_choice=nearest-unreached-seed0",
        "sgim-d-demonstration_content=goal-only-teacher_choice=nearest-unreached-timing=on-"
        "request-seed0",
        "sgim-d-teacher_choice=nearest-unreached-seed0",
        "sgim-d-teacher_choice=nearest-unreached-timing=on-request-seed0"]
    saggriac = next(r for r in runs if r.learner == "saggriac")
    assert "--param" not in saggriac.argv()
    asks = next(r for r in runs if "timing=on-request" in r.name and "goal-only" in r.name)
    assert "timing=on-request" in asks.argv() and "demonstration_content=goal-only" in (
        asks.argv())


@pytest.mark.parametrize(("document", "message"), [
    ({"learner": "demo-only", "param": {"timing": "on-request"}}, "demo-only attempts no goals"),
    ({"learner": "demo-only", "param": {"demonstration_content": ["means-only", "goal-only"]}},
     "cannot learn from a goal-only"),
    ({"learner": "sgim-d", "teacher": "external", "param": {"timing": "on-request"}},
     "needs the automatic teacher"),
])
def test_social_modes_a_learner_cannot_play_stop_the_sweep(document, message):
    with pytest.raises(SweepFileError, match=message):
        expand(document)


def test_a_list_is_one_value_when_wrapped():
    assert sweep_file.yaml_text([1, 2], "here") == "[1, 2]"
    with pytest.raises(SweepFileError, match="unknown parameter 'some_list'"):
        expand({"learner": "random", "param": {"some_list": [[1, 2]]}})


def test_default_values_make_the_default_run_once():
    runs = expand({"seeds": [3], "grid": [
        {"learner": "sgim-d"},
        {"learner": "sgim-d", "demonstration_period": 150,
         "param": {"imitation_count": 5, "explore_gain": 4}}]})
    assert [r.name for r in runs] == ["sgim-d-seed3"]
    assert "--param" not in runs[0].argv()


def test_a_teacher_parameter_at_its_default_names_no_run_apart():
    """The teacher's choice rule at its default (learner.yaml holds it beside the learner's
    parameters), written out, is the paper's run: it names no run apart."""
    runs = expand({"seeds": [0], "learner": "sgim-d",
                   "param": {"teacher_choice": ["random-unreached", "nearest-unreached"]}})
    assert [r.name for r in runs] == ["sgim-d-seed0",
                                      "sgim-d-teacher_choice=nearest-unreached-seed0"]
    assert "--param" not in runs[0].argv()
    assert runs[1].argv()[-2:] == ["--param", "teacher_choice=nearest-unreached"]


def test_seed_forms():
    assert [r.seed for r in expand({"learner": "random", "seeds": 3})] == [0, 1, 2]
    assert [r.seed for r in expand({"learner": "random", "seeds": [4, 7]})] == [4, 7]
    assert [r.seed for r in expand({"learner": "random",
                                    "seeds": {"first": 10, "count": 2}})] == [10, 11]


@pytest.mark.parametrize(("document", "message"), [
    ({"learner": "sgim-dd"}, "unknown learner 'sgim-dd'"),
    ({"learner": "sgim-d", "imitation_count": 3}, "goes under 'param:'"),
    ({"learner": "sgim-d", "param": {"demonstration_period": 50}},
     "use the setting 'demonstration_period'"),
    ({"learner": "sgim-d", "param": {"output": "x"}}, "run_experiment sets it"),
    ({"learner": "sgim-d", "param": {"explore_gian": 2}}, "did you mean 'explore_gain'"),
    ({"learner": "sgim-d", "param": {"imitation_count": [3, -1]}}, "imitation_count"),
    ({"learner": "sgim-d", "param": {"p_mode1": 0.9}}, "p_mode"),
    ({"learner": "sgim-d", "teacher": "human"}, "need a person"),
    ({"learner": "sgim-d", "seeds": -1}, "seeds must be integers >= 0"),
    ({"learner": "sgim-d", "seeds": "many"}, "seeds must be a count"),
    ({"learner": "sgim-d", "demonstration_period": 0},
     "demonstration_period must be an integer >= 1"),
    ({"learner": "sgim-d", "movements": [100, 200]}, "share the folder sgim-d-seed0"),
    ({"grid": [{"learner": "random", "runs_dir": "x"}]}, "belongs at the top"),
    ({"grid": [{"seeds": 2}]}, "no learner"),
    ({"learner": "random", "grid": []}, "non-empty list"),
    ({"learner": "random", "param": {"nested": {"a": 1}}}, "cannot be a mapping"),
])
def test_bad_files_are_refused_with_the_reason(document, message):
    with pytest.raises(SweepFileError, match=message):
        expand(document)


def test_load_names_the_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("learner: [sgim-d\n")
    with pytest.raises(SweepFileError, match=r"bad\.yaml: not valid YAML"):
        load(bad)
    with pytest.raises(SweepFileError, match="cannot read"):
        load(tmp_path / "absent.yaml")
    good = tmp_path / "good.yaml"
    good.write_text("learner: random\nrun_timeout: 60\n")
    sweep = load(good)
    assert sweep.runs_dir == REPO / "runs" / "good" and sweep.run_timeout == 60
    assert load(good, tmp_path / "elsewhere").runs_dir == tmp_path / "elsewhere"


def test_the_pinned_study_is_run_studys_study():
    """The pinned study (experiments/study.yaml) makes run_study.sh's runs, under its folder
    names, so either resumes what the other began: its defaults, and the second finding's
    seeds 10-19 of SGIM-D and demonstrations only."""
    from sgim_nodes.experiments.pinned import find

    expected = set()
    for argv in ([], ["--learners", "sgim-d", "demo-only", "--first-seed", "10", "--seeds",
                      "20"]):
        args = batch.parse_args(argv)
        expected |= {f"{learner}-seed{seed}" for seed in range(args.first_seed, args.seeds)
                     for learner in args.learners}
    runs = find("study").graph_runs
    assert len(expected) == 70 and {r.name for r in runs} == expected
    for run in runs:
        assert run.movements == args.movements and run.eval_every == args.eval_every
        assert run.params == () and run.demonstration_period in (None, 150)


def test_shipped_sweep_files_expand():
    for path in SWEEPS.glob("*.yaml"):
        assert load(path).runs, path
        yaml.safe_load(path.read_text())


@pytest.mark.parametrize(("argv", "message"), [
    (["--param", "timing=on-request"], "demo-only: .*demo-only attempts no goals"),
    (["--learners", "demo-only", "--param", "demonstration_content=goal-only"],
     "cannot learn from a goal-only"),
    (["--param", "timing=sometimes"], "'timing'"),
])
def test_run_study_checks_every_param_for_every_learner_first(argv, message, capsys):
    with pytest.raises(SystemExit):
        batch.parse_args(argv)
    assert re.search(message, capsys.readouterr().err)


def test_run_study_takes_the_social_modes_its_learners_can_play():
    args = batch.parse_args(["--learners", "sgim-d", "saggriac", "--param",
                             "timing=on-request", "--param", "demonstration_content=goal-only"])
    assert args.param == ["timing=on-request", "demonstration_content=goal-only"]
