#!/usr/bin/env bash
# Run a node as `ros2 run PKG EXE [ARGS...]` would, with or without ros2cli.
# With a full ROS 2 install, `ros2 run` is used as it is. The PyPI wheels have no ros2cli, so
# otherwise this does its lookup itself: the package prefix from the ament index on
# AMENT_PREFIX_PATH, then PREFIX/lib/PKG/EXE. The workspace environment is sourced if needed.
set -euo pipefail
if [[ $# -lt 2 || $1 == -h || $1 == --help ]]; then
  echo "usage: ros_ws/ros2run.sh PKG EXE [ARGS...]   (e.g. ros_ws/ros2run.sh sim_bridge sim_bridge --ros-args -p seed:=3)"
  [[ $# -ge 1 && ($1 == -h || $1 == --help) ]] && exit 0 || exit 2
fi
pkg="$1" exe="$2"; shift 2
if [[ -z "${SGIM_ENV_SOURCED:-}" ]]; then
  # shellcheck disable=SC1091
  source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/env.sh"
  export SGIM_ENV_SOURCED=1
fi
if command -v ros2 >/dev/null 2>&1; then
  exec ros2 run "$pkg" "$exe" "$@"
fi
IFS=: read -r -a prefixes <<<"${AMENT_PREFIX_PATH:-}"
for prefix in "${prefixes[@]}"; do
  if [[ -f "$prefix/share/ament_index/resource_index/packages/$pkg" ]]; then
    if [[ -x "$prefix/lib/$pkg/$exe" ]]; then
      exec "$prefix/lib/$pkg/$exe" "$@"
    fi
    echo "ros2run: package '$pkg' has no executable '$exe'; it has: $(ls "$prefix/lib/$pkg" 2>/dev/null | tr '\n' ' ')" >&2
    exit 1
  fi
done
echo "ros2run: package '$pkg' not found on AMENT_PREFIX_PATH (did ./bootstrap.sh build the workspace?)" >&2
exit 1
