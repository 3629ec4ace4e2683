#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh, idempotent), then run the main job: one SGIM-D
# experiment through the ROS 2 node graph, recorded to a bag, and its figures.
#   ./run.sh                 a short run: 1000 movements (about a minute)
#   ./run.sh --full          the paper's 5000 movements
#   ./run.sh --seed 3        any option of ros_ws/run_experiment.sh (see --help)
# Output: runs/main/sgim-d-<time>/ (bag, metadata, logs) with its figures in figures/.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
movements=1000
args=()
for arg in "$@"; do
  case "$arg" in
    --full) movements=5000 ;;
    -h|--help) sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) args+=("$arg") ;;
  esac
done
./bootstrap.sh
# shellcheck disable=SC1091
source ros_ws/env.sh
export SGIM_ENV_SOURCED=1
run="runs/main/sgim-d-$(date +%Y%m%d-%H%M%S)"
mkdir -p runs/main
ros_ws/run_experiment.sh sgim-d --movements "$movements" --runs-dir runs/main \
  --name "$(basename "$run")" "${args[@]}"
ros_ws/ros2run.sh sgim_nodes analyze "$run" --out "$run/figures"
echo "run.sh: the run's bag is in $run/bag, its figures and results.md in $run/figures/"
