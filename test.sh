#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh, idempotent), then lint and run the whole test suite.
# Extra arguments go to pytest, e.g. ./test.sh tests/core -x
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
./bootstrap.sh
# shellcheck disable=SC1091
source ros_ws/env.sh
ruff check .
# ROS tests must run here: a missing rclpy or sgim_msgs is an error, not a skip.
SGIM_REQUIRE_ROS=1 python -m pytest -q --timeout=600 "$@"
