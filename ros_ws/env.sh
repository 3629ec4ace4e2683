# Source this file (bash) to use the workspace: `source ros_ws/env.sh`.
# With the project's virtual environment (./bootstrap.sh), it activates it and points ROS at it;
# on a machine with a full ROS 2 Jazzy install and no venv, it sources /opt/ros/jazzy instead.
# Either way it then sources the colcon workspace and keeps DDS discovery on this host unless
# ROS_AUTOMATIC_DISCOVERY_RANGE is already set.

# colcon's and ROS's setup scripts read unset variables: relax `set -u` while sourcing them.
case $- in *u*) _sgim_nounset=1; set +u ;; *) _sgim_nounset= ;; esac
_sgim_ws="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
_sgim_venv="${SGIM_VENV:-$(dirname "$_sgim_ws")/.venv}"
if [ -x "$_sgim_venv/bin/python" ]; then
  export VIRTUAL_ENV="$_sgim_venv"
  case ":$PATH:" in *":$_sgim_venv/bin:"*) ;; *) export PATH="$_sgim_venv/bin:$PATH" ;; esac
  case ":${AMENT_PREFIX_PATH:-}:" in *":$_sgim_venv:"*) ;;
    *) export AMENT_PREFIX_PATH="$_sgim_venv${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}" ;; esac
  case ":${CMAKE_PREFIX_PATH:-}:" in *":$_sgim_venv:"*) ;;
    *) export CMAKE_PREFIX_PATH="$_sgim_venv${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}" ;; esac
elif [ -f /opt/ros/jazzy/setup.bash ]; then
  # shellcheck disable=SC1091
  . /opt/ros/jazzy/setup.bash
fi
if [ -f "$_sgim_ws/install/setup.bash" ]; then
  # shellcheck disable=SC1091
  . "$_sgim_ws/install/setup.bash"
else
  echo "ros_ws/env.sh: the workspace is not built yet: run ./bootstrap.sh first" >&2
fi
export RMW_IMPLEMENTATION="${RMW_IMPLEMENTATION:-rmw_fastrtps_cpp}"
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
[ -n "$_sgim_nounset" ] && set -u
unset _sgim_ws _sgim_venv _sgim_nounset
