#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh, idempotent), then run the main job: a short SGIM-D
# experiment on the fishing world. Its output lands in runs/; the path is printed at the end.
#   ./run.sh                      500 movements, seed 0
#   ./run.sh --movements 5000     the paper's length
#   ./run.sh --help               every option of the runner
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
./bootstrap.sh
# shellcheck disable=SC1091
source ros_ws/env.sh
out="runs/sgim-d-$(date +%Y%m%d-%H%M%S)"
mkdir -p "$out"
ros_ws/ros2run.sh sgim_nodes learn --learner sgim-d --env fishing --movements 500 --seed 0 \
  --output "$out/run.jsonl" "$@"
echo "run.sh: movements and evaluations written to $out/run.jsonl"
