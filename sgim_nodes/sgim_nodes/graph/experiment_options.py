"""The command line of `run_experiment.sh` (graph/experiment.py): its options, their defaults
and checks, apart from running the graph so that the sweep and the tests can parse a run's
options the way the launcher does.
"""

from __future__ import annotations

import argparse
import ipaddress
import math
import secrets
from collections.abc import Sequence
from pathlib import Path

from sgim_nodes.core.learner_registry import learner_names
from sgim_nodes.core.social_config import SOCIAL_DEFAULTS
from sgim_nodes.graph.description import STORAGES, TEACHERS
from sgim_nodes.graph.run_folder import run_name_problem
from sgim_ros.command_line import BriefParser, shown
from sgim_ros.params import SEED_MAX, seed_problem

REPO = Path(__file__).resolve().parents[3]
DEFAULTS = {"seed": 0, "movements": 5000, "eval_every": 250,
            "demonstration_period": SOCIAL_DEFAULTS.demonstration_period,
            "teacher": "automatic", "storage": "mcap", "wait_for_teacher": 0.0,
            "web_port": 8765, "web_host": "127.0.0.1", "web_token": "", "web_linger": 600.0,
            "no_markers": False}
# Options a resumed run takes from its folder: giving one with --resume is refused.
RUN_OPTIONS = ("seed", "movements", "eval_every", "demonstration_period", "teacher", "storage",
               "name", "param", "params_file", "wait_for_teacher", "web_port", "web_host",
               "web_token", "web_linger", "no_markers")
FOREVER = ("forever", "inf", "-1")  # --wait-for-teacher values that mean "until it acts"
WEB_TOKEN_MIN = 16  # the web teacher's own minimum (teacher.web.server.MIN_TOKEN)
HUMAN_TIMEOUT = 24 * 3600.0  # a person teaches at a person's pace


def default_timeout(movements: int, teacher: str = "automatic") -> float:
    """Generous: a 5000-movement run takes about 2 minutes on 2 free cores; this allows 25
    times that, and bounds a run whose every inner wait somehow failed to. A run taught by a
    person may wait for them (--wait-for-teacher, pause): a day."""
    if teacher in ("human", "web"):
        return HUMAN_TIMEOUT
    return 600.0 + 0.5 * movements


def is_loopback(host: str) -> bool:
    """Whether the web teacher would serve this machine only (no token needed)."""
    try:
        return host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def wait_seconds(text: str) -> float:
    """--wait-for-teacher: seconds >= 0, or forever (the arbiter's -1)."""
    if text.strip().lower() in FOREVER:
        return -1.0
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds or 'forever', got {text!r}") from None
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected seconds >= 0 or 'forever', got {text!r}")
    return value


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = BriefParser(
        prog="ros_ws/run_experiment.sh",
        description="Run one learner through the ROS 2 node graph and record the run to a bag "
                    "in runs/. Example: ros_ws/run_experiment.sh sgim-d --seed 3 "
                    "--movements 5000. Exit codes: 0 finished, 1 failed, 2 refused, "
                    "130 Ctrl-C.")
    p.add_argument("learner", choices=learner_names(), nargs="?",
                   help="which learner to run (not with --resume)")
    p.add_argument("--resume", type=Path, metavar="RUN_DIR",
                   help="resume an interrupted or failed run from its recordings, to its "
                        "movement budget; the new recording goes beside the old ones "
                        "(bag.resumeN). The run keeps its own options and parameters")
    p.add_argument("--seed", type=int, help="seed of the run (default: 0)")
    p.add_argument("--movements", type=int,
                   help="movement budget; the paper's is 5000 (default: 5000)")
    p.add_argument("--eval-every", type=int,
                   help="movements between evaluations; paper 250 (default: 250)")
    p.add_argument("--demonstration-period", type=int,
                   help="movements between demonstrations, the paper's P (default: "
                        f"{DEFAULTS['demonstration_period']})")
    p.add_argument("--teacher", choices=TEACHERS,
                   help="automatic (default): the teacher node, every --demonstration-period "
                        "movements; human: you, at the human_input prompt in this terminal; "
                        "web: you, on the web_teacher page (its address is printed); external: "
                        "no teacher node, demonstrations come from any other publisher at any "
                        "time")
    p.add_argument("--wait-for-teacher", type=wait_seconds, metavar="SECONDS",
                   help="human or web teacher: stop every --demonstration-period movements "
                        "and wait this long for a demonstration (0: never wait; 'forever': "
                        "until the teacher demonstrates or resumes). Default: 0")
    p.add_argument("--web-port", type=int,
                   help="web teacher: the page's port (0: any free one; default 8765)")
    p.add_argument("--web-host",
                   help="web teacher: the interface to serve on (default: 127.0.0.1, this "
                        "machine only; another one needs an access token, generated unless "
                        "--web-token)")
    p.add_argument("--web-token",
                   help="web teacher: the access token the page's address must carry")
    p.add_argument("--web-linger", type=float, metavar="SECONDS",
                   help="web teacher: once the run is over, its page stays while someone "
                        "looks at it, until closed there or for this long (0: it ends with "
                        "the run; a run nobody watches ends at once anyway). Default: 600")
    p.add_argument("--no-markers", action="store_const", const=True,
                   help="do not start the markers node (MarkerArray topics for rviz2 and "
                        "Foxglove, recorded in the bag)")
    p.add_argument("--runs-dir", type=Path, default=REPO / "runs",
                   help="where the run folder is made (default: runs/)")
    p.add_argument("--name", help="run folder name (default: <learner>-seed<N>-<time>)")
    p.add_argument("--storage", choices=STORAGES, help="bag storage (default: mcap)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="set a node parameter, e.g. --param goal_budget=20 (VALUE is YAML); "
                        "the social modes too: timing=on-request, demonstration_content="
                        "goal-only or means-only, teacher_choice=farthest-unreached; a name no "
                        "node declares, or a mode the learner cannot play, stops the run before "
                        "it starts")
    p.add_argument("--params-file", action="append", default=[], type=Path, metavar="FILE",
                   help="a ROS parameter file: sections /** (every node) or a node's name, "
                        "each holding ros__parameters; checked like --param, which wins")
    p.add_argument("--prefix", action="append", default=[], metavar="NODE=COMMAND",
                   help="start NODE under COMMAND, as a launch file's prefix does (e.g. "
                        "--prefix 'sim_bridge=valgrind', --prefix 'recorder=prlimit "
                        "--fsize=1000000')")
    p.add_argument("--separate", action="store_true",
                   help="one process per node, each on its own executor (default: the nodes "
                        "that only pass messages share one process; docs/node_graph.md, "
                        "\"Processes\")")
    p.add_argument("--compose", action="append", default=[], metavar="NAME=NODE,NODE,...",
                   help="these nodes share process NAME, instead of the default grouping "
                        "(repeat for several processes; nodes named in none run alone)")
    p.add_argument("--domain", type=int, default=None,
                   help="run in this ROS_DOMAIN_ID, e.g. to join a graph from a test; "
                        "refused while another run holds it (default: a free one, which the "
                        "run holds until its last process ends)")
    p.add_argument("--timeout", type=float, default=None,
                   help="fail the run after this many seconds (> 0; default: 600 + 0.5 per "
                        "movement, 3100 s for 5000 movements; a day with a human or web "
                        "teacher)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    if (args.learner is None) == (args.resume is None):
        p.error("give a learner, or --resume RUN_DIR (not both)")
    if args.resume is not None:
        given = [f"--{name.replace('_', '-')}" for name in RUN_OPTIONS
                 if getattr(args, name) not in (None, [])]
        if given:
            p.error(f"{', '.join(given)} cannot be given with --resume: a resumed run keeps "
                    "the options and parameters it was started with")
    for name, value in DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    for name in ("movements", "demonstration_period"):
        if getattr(args, name) < 1:
            p.error(f"--{name.replace('_', '-')} must be >= 1")
    if seed_problem(args.seed):
        p.error(f"--seed must be in 0..{SEED_MAX} (2**32 - 1): the graph carries it in a "
                "uint32")
    if args.eval_every < 0:
        p.error("--eval-every must be >= 0")
    if args.name is not None and run_name_problem(args.name):
        p.error(f"--name {shown(args.name)}: {run_name_problem(args.name)}")
    if args.timeout is not None and not (args.timeout > 0 and math.isfinite(args.timeout)):
        p.error(f"--timeout must be a number of seconds > 0, got {args.timeout:g}")
    if args.domain is not None and not 0 <= args.domain <= 232:
        p.error(f"--domain must be in 0..232, got {args.domain}")
    if not 0 <= args.web_port <= 65535:
        p.error("--web-port must be in 0..65535")
    if not (args.web_linger >= 0 and math.isfinite(args.web_linger)):
        p.error(f"--web-linger must be a number of seconds >= 0, got {args.web_linger:g}")
    if args.teacher == "web":
        if not is_loopback(args.web_host) and not args.web_token:
            args.web_token = secrets.token_urlsafe(18)
        if args.web_token and len(args.web_token) < WEB_TOKEN_MIN:
            p.error(f"--web-token must have at least {WEB_TOKEN_MIN} characters")
    if args.wait_for_teacher and args.teacher not in ("human", "web"):
        p.error("--wait-for-teacher needs a human teacher (--teacher human or web)")
    return args
