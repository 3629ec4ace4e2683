#!/usr/bin/env bash
# Run a sweep file: every run through the node graph as a Ray task, resumable.
#   ros_ws/run_sweep.sh sgim_nodes/config/sweeps/example.yaml          # Ray started here
#   ros_ws/run_sweep.sh SWEEP.yaml --address HEAD_IP:6379               # on a Ray cluster
#   ros_ws/run_sweep.sh --help
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
export SGIM_ENV_SOURCED=1
exec python -m sgim_nodes.sweep.driver "$@"
