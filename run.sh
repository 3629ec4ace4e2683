#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh, idempotent), then run the main job: one SGIM-D
# experiment through the ROS 2 node graph, recorded to a bag, and its figures.
#   ./run.sh                 a short run: 1000 movements (a few minutes)
#   ./run.sh --full          the paper's 5000 movements
#   ./run.sh --seed 3        any option of ros_ws/run_experiment.sh (see --help)
# Output: runs/main/sgim-d-seed<N>-<time>/ (bag, metadata, logs) and its figures in
# runs/main/figures/.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
movements=1000
args=()
for arg in "$@"; do
  case "$arg" in
    --full) movements=5000 ;;
    -h|--help) sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) args+=("$arg") ;;
  esac
done
./bootstrap.sh
# shellcheck disable=SC1091
source ros_ws/env.sh
export SGIM_ENV_SOURCED=1
mkdir -p runs/main
ros_ws/run_experiment.sh sgim-d --movements "$movements" --runs-dir runs/main "${args[@]}"
ros_ws/ros2run.sh sgim_nodes analyze runs/main --out runs/main/figures
echo "run.sh: the run's bag is in runs/main/<run>/bag, its figures in runs/main/figures/"
