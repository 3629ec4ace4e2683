"""The arbiter's (social_interaction's) parameters: declared with defaults, ranges and read-only
flags, apart from the node so that its schedule reads without them. The graph's description
reads them through the node module, as for every node (graph/description.py).
"""

from __future__ import annotations

from sgim_nodes.nodes.pace import FOREVER
from sgim_nodes.nodes.ros_glue import TEACHERS, learner_node_params, social_params
from sgim_nodes.nodes.sim_client import SIM_CLIENT_PARAMS
from sgim_ros.params import Param, at_least, non_negative, one_of, positive
from sim_bridge.data_params import TEACHING_SET_FILE

TEACHER_TIMEOUT_MIN = 1.0
"""The shortest wait for a teacher, in seconds. An answer comes only after the teacher has
heard the movements up to the turn and cast, in its own world, the learner's model for the
teaching goals it checks (or, for a request, made the demonstration it shows): casts as long
as the run's own movements, then messages between nodes. A wait shorter than a second ends a
healthy run at its first turn on a busy machine, and is never what one means: the default is a
minute, an hour when a person answers."""
PARAMS = learner_node_params(
    Param("movements", 5000, "the run's movement budget (the paper: 5000)", at_least(1)),
    Param("teacher", "automatic", "who gives demonstrations: automatic (synchronous at its "
          "period), human (any time), none", one_of("automatic", "human", "none")),
    *social_params("demonstration_period", "timing"),
    Param("wait_for_teacher", 0.0, "human teacher: seconds the run waits for a demonstration "
          f"every demonstration_period movements (0: never waits, {FOREVER:g}: until the "
          "teacher acts)", lambda v: v >= 0 or v == FOREVER, f">= 0 or {FOREVER:g}"),
    Param("wait_for_evaluation", True, "finish only after the final evaluation"),
    Param("wait_for_recorder", True, "start only once a recorder listens"),
    Param("startup_timeout", 120.0, "seconds to wait for the other nodes (their servers, "
          "publishers and the listeners' *_ready services, sgim_ros/ready.py) before the start",
          positive),
    Param("teacher_timeout", 60.0, "seconds to wait for the teacher at a boundary, or for "
          "the answer to a request (sgim-acts; 3600 when the web page is one of its teachers); "
          "never under a second: a teacher answers only after casting in its own world",
          at_least(TEACHER_TIMEOUT_MIN), read_only=False),
    Param("call_timeout", 600.0, "seconds to wait for the answer of register_demonstration, "
          "or for the result of a reach_goal or imitate job", positive, read_only=False),
    Param("goals_per_job", 50, "goals one reach_goal job may attempt before it reports back "
          "(it stops earlier at the teacher's boundary, the budget, a pause or a "
          "demonstration): a job's length stays bounded for call_timeout and progress; 1 "
          "sends each goal as a job of its own, as timing 'on-request' always does (the "
          "help rule decides after each goal) and a goal-only demonstration does (its goal "
          "is the job's only one)", at_least(1)),
    Param("evaluation_timeout", 600.0, "seconds to wait for the final evaluation", positive,
          read_only=False),
    TEACHERS,
    *SIM_CLIENT_PARAMS,
    Param("settle_time", 2.0, "seconds of discovery settling before the start", non_negative),
    Param("teaching_set", "", "the teacher's teaching-set file (empty: the packaged one), to "
          "validate demonstrations' teaching-set indices", TEACHING_SET_FILE),
)
