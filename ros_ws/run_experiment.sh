#!/usr/bin/env bash
# Run one learner through the ROS 2 node graph; one bag per run in runs/.
#   ros_ws/run_experiment.sh sgim-d --seed 3 --movements 5000
#   ros_ws/run_experiment.sh --help
# Each node is started as `ros2 run PKG EXE` would (ros_ws/ros2run.sh), in a ROS domain of its
# own with discovery kept on this host. Ctrl-C stops every node and leaves a readable bag.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
export SGIM_ENV_SOURCED=1
exec python -m sgim_nodes.graph.experiment "$@"
