"""The parameter files say what the core's declarations say: LearnerConfig and SocialConfig."""

from dataclasses import fields

import yaml

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.social_config import SocialConfig
from tests.conftest import REPO


def test_learner_yaml_holds_every_learner_default():
    text = (REPO / "sgim_nodes" / "config" / "learner.yaml").read_text()
    values = yaml.safe_load(text)["/**"]["ros__parameters"]
    default = LearnerConfig()
    for f in fields(LearnerConfig):
        assert values[f.name] == getattr(default, f.name), f.name
    # The run's own settings are the paper's.
    assert values["movements"] == 5000 and values["eval_every"] == 250
    assert values["action_size"] == 24
    social = SocialConfig()
    for name in ("demonstration_period", "timing", "demonstration_content", "teacher_choice"):
        assert values[name] == getattr(social, name), name


def test_learner_yaml_comments_are_the_config_docstrings():
    import runpy

    tool = runpy.run_path(str(REPO / "ros_ws" / "write_learner_yaml.py"))
    assert tool["expected_text"]() == (REPO / "sgim_nodes" / "config" / "learner.yaml").read_text(
    ), "run ros_ws/write_learner_yaml.py"
    assert tool["expected_teacher_text"]() == (
        REPO / "teacher" / "config" / "teacher.yaml").read_text(), "run write_learner_yaml.py"


def test_node_parameter_files_hold_the_code_defaults():
    from sim_bridge.fishing_world import DEFAULT_NOISE, DEFAULT_TIME_STEP

    sim = yaml.safe_load((REPO / "sim_bridge" / "config" / "sim_bridge.yaml").read_text())
    values = sim["sim_bridge"]["ros__parameters"]
    assert values["noise"] == DEFAULT_NOISE and values["time_step"] == DEFAULT_TIME_STEP
    teacher = yaml.safe_load((REPO / "teacher" / "config" / "teacher.yaml").read_text())
    values = teacher["teacher"]["ros__parameters"]
    social = SocialConfig()
    for name in ("demonstration_period", "reached_rule", "teacher_choice",
                 "demonstration_content", "timing", "tolerance_noise"):
        assert values[name] == getattr(social, name), name


def test_a_run_recorded_before_a_field_existed_resumes_as_it_ran():
    """recorded_learner: a recording without local_step_check (made before it existed) gets
    the value that does what the learner did then; a complete recording gets nothing."""
    from sgim_nodes.core.config import BEFORE_IT_EXISTED, LearnerConfig, recorded_learner

    complete = LearnerConfig().to_dict()
    assert recorded_learner(complete) == ({}, [])
    older = {k: v for k, v in complete.items() if k not in ("local_step_check", "zeta")}
    earlier, unknown = recorded_learner(older)
    assert earlier == {"local_step_check": "none"} and unknown == ["zeta"]
    assert LearnerConfig(**{**older, **earlier}).local_step_check == "none"
    for name, value in BEFORE_IT_EXISTED.items():  # every such value is a valid setting
        LearnerConfig(**{name: value})
