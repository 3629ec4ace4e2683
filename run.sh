#!/usr/bin/env bash
# Set up what is missing (./bootstrap.sh, idempotent), then run the main job: one SGIM-D
# experiment through the ROS 2 node graph, recorded to a bag, and its figures.
#   ./run.sh                 a short run: 1000 movements (about a minute)
#   ./run.sh --full          the paper's 5000 movements
#   ./run.sh --seed 3        any option of ros_ws/run_experiment.sh (see --help)
# Output: runs/main/sgim-d-<time>/ (or --runs-dir/--name) with its figures in figures/.
set -euo pipefail
# No cd: a relative path given as an option (--runs-dir, --params-file) is the caller's.
here="$(dirname "${BASH_SOURCE[0]}")"
movements=1000
runs_dir="$here/runs/main"
name="sgim-d-$(date +%Y%m%d-%H%M%S)"
args=()
# --runs-dir and --name are the launcher's too; read here so that analyze finds the run.
while (($#)); do
  case "$1" in
    --full) movements=5000 ;;
    -h|--help) sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --runs-dir=*) runs_dir="${1#*=}" ;;
    --name=*) name="${1#*=}" ;;
    --runs-dir|--name)
      if (($# < 2)); then args+=("$1"); else  # no value: the launcher refuses it
        if [[ "$1" == --runs-dir ]]; then runs_dir="$2"; else name="$2"; fi
        shift
      fi ;;
    *) args+=("$1") ;;
  esac
  shift
done
"$here/bootstrap.sh"
# shellcheck disable=SC1091
source "$here/ros_ws/env.sh"
export SGIM_ENV_SOURCED=1
run="$runs_dir/$name"
mkdir -p "$runs_dir"
"$here/ros_ws/run_experiment.sh" sgim-d --movements "$movements" --runs-dir "$runs_dir" \
  --name "$name" "${args[@]}"
"$here/ros_ws/ros2run.sh" sgim_nodes analyze "$run" --out "$run/figures"
echo "run.sh: the run's bag is in $run/bag, its figures and results.md in $run/figures/"
