#!/usr/bin/env bash
# Make a pinned experiment (experiments/NAME.yaml): its runs (resumable, here or on Ray), its
# analysis, and its page's generated blocks and figures. --help for the options.
#   ros_ws/reproduce.sh study              the paper's study -> docs/results.md
#   ros_ws/reproduce.sh --list             every experiment, its pages and whether they are fresh
#   ros_ws/reproduce.sh --check            fail on a stale page without its banner (./test.sh)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
export SGIM_ENV_SOURCED=1
exec python -m sgim_nodes.experiments.cli "$@"
