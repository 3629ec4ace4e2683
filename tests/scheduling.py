"""How `./test.sh` shares the suite between its workers (pytest-xdist, one per core).

A test file is one unit of work, run whole by one worker in its own order: its module
fixtures (a run several tests read, a browser page, a Ray cluster) are made once. The tests of
a file in SPLIT share nothing costly, so each is a unit of its own and both workers take some.
The files of a group in GROUPS are one unit: they must not run at the same time (two Ray
clusters at once, ...). Test ids stay those of a serial run (no `@group` suffix as with
xdist's loadgroup), so a failure is named as before and `./test.sh <that id>` runs it again.

Units start longest first (SECONDS: about what each took in a `--durations=0` run on 2
cores), so that the two longest run side by side on the two workers and no long unit is left
for the end while the other worker idles. A file not listed counts as short.

A worker that dies mid-test (a segmentation fault in a C extension, a kill) fails that test
by name with the signal that ended it. The rest of its units go back to the front of the
queue for the worker that replaces it, or for the others; units it had finished stay done.
xdist's own scope scheduling re-sends a dead worker's finished units as empty batches that
no worker ever answers, and re-runs the crashing test until its restarts run out: the suite
hung, so this module does not leave a crash to it.
"""

from __future__ import annotations

import signal
from collections import Counter
from typing import Any

# Files whose tests each make what they need (their own graph run): one unit per test.
SPLIT = frozenset({
    "tests/core/test_inverse_model.py",
    "tests/core/test_learners.py",
    "tests/packaging/test_crashed_worker.py",
    "tests/ros/test_faults.py",
    "tests/ros/test_first_hour.py",
    "tests/ros/test_graph_runs.py",
    "tests/ros/test_launcher_faults.py",
    "tests/ros/test_pace.py",
    "tests/teacher/test_human_input_node.py",
})

# Files that must not run at the same time as each other: one unit, one worker. Ray: a
# cluster of two nodes and a sweep's own local Ray would share the machine's Ray defaults.
GROUPS: dict[str, tuple[str, ...]] = {
    "ray": ("tests/sweep/test_ray_cluster.py", "tests/sweep/test_driver_signals.py"),
}

# Seconds per unit (group, file, test, or all the parameters of a test), from a
# `./test.sh --durations=0` run; only their order matters, within a factor of two or so.
SECONDS: dict[str, float] = {
    "ray": 248,
    "tests/ros/test_graph_runs.py::test_learner_through_the_graph": 174,
    "tests/core/test_learners.py::test_goal_babbling_beats_random_on_the_twenty_joint_arm": 34,
    "tests/ros/test_faults.py::test_an_interrupted_run_resumes_from_its_recording_to_the_"
    "same_final_count": 72,
    "tests/experiments/test_reproduce_graph.py": 224,
    "tests/ros/test_pace.py::test_wait_for_teacher_seconds_ends_each_turn_and_zero_never_"
    "waits": 69,
    "tests/core/test_portable.py": 63,
    "tests/ros/test_resume_turns.py": 58,
    "tests/ros/test_rogue_records.py": 56,
    "tests/ros/test_graph_runs.py::test_the_teachers_choice_rule_through_the_graph": 53,
    "tests/ros/test_graph_runs.py::test_an_interrupted_sgim_acts_run_resumes_and_goes_on_"
    "asking": 70,
    "tests/ros/test_acts_web_teacher.py": 51,
    "tests/ros/test_graph_runs.py::test_teachers_taking_turns_through_the_graph": 46,
    "tests/ros/test_graph_runs.py::test_sgim_acts_through_the_graph": 41,
    "tests/browser/test_web_teacher_page.py": 45,
    "tests/ros/test_graph_runs.py::test_means_only_demonstrations_through_the_graph": 43,
    "tests/ros/test_launcher_faults.py::test_a_killed_launcher_leaves_no_node_and_holds_its_"
    "domain_until_they_end": 43,
    "tests/ros/test_graph_runs.py::test_on_request_timing_through_the_graph": 42,
    "tests/ros/test_graph_runs.py::test_goal_only_demonstrations_through_the_graph": 40,
    "tests/ros/test_pace.py::test_turns_step_pause_and_the_end_of_the_run_at_the_prompt": 40,
    "tests/ros/test_graph_runs.py::test_where_reach_goal_jobs_end_changes_no_movement": 39,
    "tests/ros/test_graph_runs.py::test_the_own_movements_rule_s_checks_through_the_graph": 36,
    "tests/bag/test_recorder_node.py": 35,
    "tests/ros/test_graph_runs.py::test_the_human_teacher_script_drives_a_run_through_the_"
    "prompt": 34,
    "tests/ros/test_full_disk.py": 34,
    "tests/teacher/test_human_input_node.py::test_a_terminal_gets_line_editing_history_and_"
    "news_above_the_prompt": 32,
    "tests/ros/test_recorder_ready.py": 30,
    "tests/benchmarks/test_bench_learners_cli.py": 29,
    "tests/ros/test_faults.py::test_a_killed_simulator_is_restarted_and_no_movement_is_lost_"
    "or_doubled": 29,
    "tests/core/test_inverse_model.py::test_never_worse_than_the_nearest_neighbour_on_the_"
    "same_memory": 28,
    "tests/ros/test_markers.py": 27,
    "tests/ros/test_sim_bridge_node.py": 26,
    "tests/ros/test_launcher_faults.py::test_a_recorder_that_cannot_write_fails_the_run_and_"
    "resume_repairs_it": 26,
    "tests/bag/test_replay.py": 25,
    "tests/ros/test_graph_runs.py::test_a_demonstration_mid_goal_is_handled_at_the_next_"
    "movement_boundary": 25,
    "tests/analysis/test_cli.py": 24,
    "tests/ros/test_bad_input.py": 24,
    "tests/ros/test_launcher_faults.py::test_a_run_longer_than_its_timeout_fails_and_says_"
    "so": 23,
    "tests/packaging/test_core_without_ros.py": 60,
    "tests/ros/test_launcher_faults.py::test_a_simulator_that_never_answers_ends_the_run_"
    "with_a_message": 18,
    "tests/ros/test_parameters_live.py": 17,
    "tests/ros/test_goal_jobs.py": 36,
    "tests/experiments/test_references.py": 53,
    "tests/ros/test_first_hour.py::test_run_sh_honours_runs_dir_and_name": 19,
    "tests/ros/test_launcher_faults.py::test_a_second_run_asking_for_a_run_s_domain_is_"
    "refused": 15,
    "tests/packaging/test_crashed_worker.py::test_a_crashed_worker_fails_its_test_and_the_"
    "run_ends": 36,
    "tests/analysis/test_pooling.py": 16,
    "tests/ros/test_launcher_faults.py::test_ctrl_c_with_output_piped_stops_every_node": 14,
    "tests/ros/test_node_parameters.py": 13,
}

_GROUP_OF = {path: name for name, paths in GROUPS.items() for path in paths}


def file_of(nodeid: str) -> str:
    return nodeid.split("::", 1)[0]


def unit_of(nodeid: str) -> str:
    """The unit of work a test belongs to: its group, its file, or itself."""
    path = file_of(nodeid)
    if path in _GROUP_OF:
        return _GROUP_OF[path]
    return nodeid if path in SPLIT else path


def base_id(nodeid: str) -> str:
    """A test's id without its parameters: test_x[a] -> test_x."""
    return nodeid.split("[", 1)[0]


def weight(unit: str, tests: int, per_file: Counter[str]) -> float:
    """A unit's expected seconds: its own entry in SECONDS, its parametrized test's, an even
    share of its file's, else a short test's."""
    for key in (unit, base_id(unit)):
        if key in SECONDS:
            return SECONDS[key] / (1 if key == unit else per_file[key] or 1)
    path = file_of(unit)
    if path in SECONDS and path != unit:
        return SECONDS[path] / (per_file[path] or 1)
    return 0.1 * tests


def make_scheduler(config: Any, log: Any) -> Any:
    """xdist's scope scheduling with our units, sent longest first."""
    from xdist.scheduler import LoadScopeScheduling

    class Scheduling(LoadScopeScheduling):
        _ordered = False

        def _split_scope(self, nodeid: str) -> str:
            return unit_of(nodeid)

        def _assign_work_unit(self, node: Any) -> None:
            if not self._ordered:  # the first call: the queue holds every unit
                self._ordered = True
                per_file = Counter(file_of(n) for n in self.collection or ())
                per_file.update(base_id(n) for n in self.collection or ())
                units = sorted(self.workqueue.items(),
                               key=lambda item: -weight(item[0], len(item[1]), per_file))
                self.workqueue.clear()
                self.workqueue.update(units)
            super()._assign_work_unit(node)

        def _reschedule(self, node: Any) -> None:
            super()._reschedule(node)
            # A worker holds back its last test until it gets another or is told to stop, so
            # a worker with one test to run (a replacement given a dead worker's last test)
            # gets a second, or is told to stop once nothing is left to send.
            while (self.workqueue and not node.shutting_down
                   and self._pending_of(self.assigned_work[node]) < 2):
                self._assign_work_unit(node)
            if not self.workqueue and not node.shutting_down:
                node.shutdown()

        def remove_node(self, node: Any) -> str | None:
            """A worker left: at the end of its work, or dead. Returns the test it died in."""
            workload = self.assigned_work.pop(node)
            crashed = first_unfinished(workload)
            if crashed is None:
                return None
            DEATHS[crashed] = death_of(node)
            workload[self._split_scope(crashed)][crashed] = True  # failed, never run again
            requeue(self.workqueue, workload)
            for other in self.assigned_work:
                self._reschedule(other)
            return crashed

    config.option.loadscopereorder = False
    return Scheduling(config, log)


# What ended each worker that died, by the test it died in, for its failure's message.
DEATHS: dict[str, str] = {}


def first_unfinished(workload: dict[str, dict[str, bool]]) -> str | None:
    """The test a worker was running when it died: its first unfinished one, as a worker runs
    its units' tests in the order they were sent."""
    for unit in workload.values():
        for nodeid, finished in unit.items():
            if not finished:
                return nodeid
    return None


def requeue(queue: dict[str, dict[str, bool]], workload: dict[str, dict[str, bool]]) -> None:
    """Put a dead worker's unfinished units back at the front of the queue, in their order;
    its finished units stay done (sent again, they would be an empty batch never answered)."""
    unfinished = [(unit, tests) for unit, tests in workload.items() if not all(tests.values())]
    for unit, tests in reversed(unfinished):
        queue[unit] = tests
        queue.move_to_end(unit, last=False)  # type: ignore[attr-defined]


def death_of(node: Any, wait_s: float = 2.0) -> str:
    """How a dead worker's process ended: 'killed by SIGSEGV', 'exit code 3', or 'ended'."""
    popen = getattr(getattr(getattr(node, "gateway", None), "_io", None), "popen", None)
    if popen is None:
        return "ended"
    try:
        code = popen.wait(timeout=wait_s)
    except Exception:
        return "ended"
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
