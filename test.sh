#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh and Debian's chromium, idempotent), lint with ruff,
# then run the tests.
#
#   ./test.sh            the whole suite, on every core: pytest-xdist workers, two more than
#                        the cores (SGIM_TEST_WORKERS=N for another count), each in a ROS
#                        domain of its own; a worker takes whole test files, the longest first
#                        (tests/scheduling.py).
#   ./test.sh --quick    the developer's loop: the pure-Python tests only (not marked ros or
#                        slow), on every core; no ROS graph or node is started.
#   ./test.sh ARGS...    extra arguments go to pytest, e.g. ./test.sh tests/core -x;
#                        -n 0 runs in this one process (pdb, -s, reading the order of events).
#   ./test.sh --quick ARGS...   both.
#   ./test.sh --help     this text.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
quick=0
case "${1:-}" in
  -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  --quick) quick=1; shift ;;
esac
./bootstrap.sh
# The browser tests (tests/browser) drive Debian's Chromium headless: install it once.
if [[ $quick == 0 ]] && ! command -v chromium >/dev/null 2>&1; then
  echo "[test] installing Debian's chromium for the browser tests (once)" >&2
  sudo=""
  [[ $(id -u) == 0 ]] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    chromium fonts-dejavu-core >/dev/null
fi
# shellcheck disable=SC1091
source ros_ws/env.sh
ruff check .
if [[ $quick == 1 ]]; then
  # Pure Python, bound by the CPU: one worker per core.
  workers="${SGIM_TEST_WORKERS:-$(nproc)}"
  # A test that reaches for a ROS domain here fails: it lacks its `ros` mark (tests/conftest.py).
  SGIM_TEST_QUICK=1 python -m pytest -q --timeout=600 -n "$workers" -m "not ros and not slow" \
    "$@"
else
  # Two workers more than the cores: the graph tests spend part of their time waiting (for
  # discovery, a teacher's turn, a timeout they test), and the extra workers fill those waits
  # (the counts measured against each other: docs/notes/measurements.md).
  workers="${SGIM_TEST_WORKERS:-$(( $(nproc) + 2 ))}"
  # ROS tests must run here: a missing rclpy or sgim_msgs is an error, not a skip.
  SGIM_REQUIRE_ROS=1 python -m pytest -q --timeout=600 -n "$workers" "$@"
fi
