"""The launcher's own plumbing: messages that survive a closed pipe, reasons quoted from logs."""

from __future__ import annotations

import os

from sgim_nodes.graph.supervise import SafeStream, log_reason


def test_messages_survive_a_closed_output_pipe_and_still_reach_the_run_log(tmp_path):
    read_end, write_end = os.pipe()
    stream = SafeStream(os.fdopen(write_end, "w"))
    stream.log = open(tmp_path / "launcher.log", "w")  # noqa: SIM115
    stream.write("before\n")
    assert os.read(read_end, 100) == b"before\n"
    os.close(read_end)  # `| tee log`, and tee is gone
    stream.write("interrupted by SIGINT\n")  # no BrokenPipeError
    stream.write("after\n")
    stream.flush()
    assert stream.broken
    stream.log.close()
    assert (tmp_path / "launcher.log").read_text() == "before\ninterrupted by SIGINT\nafter\n"


def test_the_reason_quoted_is_the_first_logged_error(tmp_path):
    log = tmp_path / "recorder.log"
    log.write_text(
        "\x1b[37;1m2026 [RTPS_TRANSPORT_SHM Error] Failed to create segment\n"
        "[INFO] [1796.1] [recorder]: recording 7 topics\n"
        "[ERROR] [1796.2] [recorder]: could not write the bag: [Errno 28] No space left\n"
        "[ERROR] [1796.3] [recorder]: could not write a movements message: part exists\n")
    assert log_reason(log) == "could not write the bag: [Errno 28] No space left"


def test_without_a_logged_error_the_reason_is_the_exception_of_a_traceback(tmp_path):
    log = tmp_path / "evaluator.log"
    log.write_text("Traceback (most recent call last):\n  File \"x.py\", line 1\n"
                   "ValueError: data must be finite\n")
    assert log_reason(log) == "ValueError: data must be finite"
    assert log_reason(tmp_path / "missing.log") == ""
