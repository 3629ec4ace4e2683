#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh and Debian's chromium, idempotent), then lint and run
# the whole test suite.
# Extra arguments go to pytest, e.g. ./test.sh tests/core -x
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
./bootstrap.sh
# The browser tests (tests/browser) drive Debian's Chromium headless: install it once.
if ! command -v chromium >/dev/null 2>&1; then
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
# ROS tests must run here: a missing rclpy or sgim_msgs is an error, not a skip.
SGIM_REQUIRE_ROS=1 python -m pytest -q --timeout=600 "$@"
