#!/usr/bin/env bash
# Set up everything this project needs, idempotently:
#   1. check the prerequisites (Python 3.11, a C++ compiler, cmake);
#   2. create .venv with ROS 2 Jazzy from PyPI and the pinned Python packages;
#   3. patch the wheels' CMake files that point at the wheel builder's paths;
#   4. colcon-build the workspace ros_ws/ (our four packages, built in place);
#   5. compile our modules' bytecode, which PYTHONDONTWRITEBYTECODE would leave unwritten.
# A second run with nothing changed only compares fingerprints (well under 5 s).
#
# Usage: ./bootstrap.sh [--force]     (--force redoes every step)
# Environment: SGIM_PYTHON   the Python 3.11 interpreter to use (default: python3.11)
#              SGIM_VENV     where the virtual environment lives (default: <repo>/.venv)
set -euo pipefail

REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
VENV="${SGIM_VENV:-$REPO/.venv}"
PYTHON="${SGIM_PYTHON:-python3.11}"
WS="$REPO/ros_ws"
FORCE=0
case "${1:-}" in
  --force) FORCE=1 ;;
  -h|--help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  "") ;;
  *) echo "bootstrap.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
esac

say() { printf '[bootstrap] %s\n' "$*" >&2; }
die() { printf '[bootstrap] error: %s\n' "$*" >&2; exit 1; }

# 1. Prerequisites: say exactly what to install when something is missing.
command -v "$PYTHON" >/dev/null 2>&1 ||
  die "$PYTHON not found. Install Python 3.11 (Debian 12: apt-get install python3.11 python3.11-venv python3.11-dev), or set SGIM_PYTHON to a Python 3.11 interpreter."
"$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' ||
  die "$PYTHON is $("$PYTHON" --version 2>&1), but the ROS 2 Jazzy wheels need Python 3.11 exactly. Set SGIM_PYTHON to a Python 3.11 interpreter."
"$PYTHON" -c 'import venv, ensurepip' 2>/dev/null ||
  die "$PYTHON has no venv/ensurepip module. Install it (Debian 12: apt-get install python3.11-venv)."
command -v c++ >/dev/null 2>&1 || command -v g++ >/dev/null 2>&1 ||
  die "no C++ compiler found; the interface package compiles C/C++ type support. Install one (Debian 12: apt-get install g++)."
command -v cmake >/dev/null 2>&1 ||
  die "cmake not found; colcon builds the interface package with it. Install it (Debian 12: apt-get install cmake)."

# Fingerprints decide what must be redone: the requirements for the venv, every file that
# shapes the build (package manifests, setup files, interface definitions) for colcon.
fingerprint() {
  (cd "$REPO" && find "$@" -type f \( -name package.xml -o -name setup.py -o -name setup.cfg \
      -o -name CMakeLists.txt -o -name '*.msg' -o -name '*.srv' -o -name '*.action' \
      -o -path '*/data/*.npz' -o -path '*/config/*.yaml' -o -path '*/resource/*' -o -path 'sgim_msgs/sgim_ros/*.py' \) -print0 2>/dev/null |
    sort -z | xargs -0 sha256sum) | sha256sum | cut -c1-16
}
REQ_STAMP="$VENV/.sgim-requirements"
TOOLS_STAMP="$VENV/.sgim-build-tools"
BUILD_STAMP="$WS/install/.sgim-build"
req_sum="$( (sha256sum "$REPO/requirements.txt"; "$PYTHON" --version) | sha256sum | cut -c1-16)"

# 2. The virtual environment.
if [[ $FORCE == 1 || ! -x "$VENV/bin/python" || "$(cat "$REQ_STAMP" 2>/dev/null)" != "$req_sum" ]]; then
  if [[ ! -x "$VENV/bin/python" ]]; then
    say "creating the virtual environment in $VENV"
    "$PYTHON" -m venv "$VENV"
  fi
  say "installing the pinned Python packages (ROS 2 Jazzy wheels included; about a minute the first time)"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --upgrade pip
  # Bytecode is compiled after, on every core: pip compiles one file at a time (45 s in all
  # against 28 + 9 s, docs/notes/measurements.md). Without bytecode, every process would
  # compile numpy and rclpy again where PYTHONDONTWRITEBYTECODE is set.
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-compile \
    -r "$REPO/requirements.txt"
  "$VENV/bin/python" -m compileall -q -j 0 "$("$VENV/bin/python" -c \
    'import sysconfig; print(sysconfig.get_paths()["purelib"])')" >/dev/null 2>&1 ||
    true  # a package's non-Python file (a template) may not compile; pip skips those too
  # 3. The wheels' CMake exports name the wheel builder's Python paths; point them here.
  say "pointing the ROS wheels' CMake files at this machine's Python"
  "$VENV/bin/python" "$REPO/ros_ws/fix_wheel_cmake_paths.py" "$VENV"
  echo "$req_sum" > "$REQ_STAMP"
  # New ROS packages, colcon or code generators may change what the build produces; another
  # pinned package (a test tool) changes nothing there, and rebuilds nothing.
  tools_sum="$(grep -iE '^(ros-|colcon|setuptools|empy|lark|catkin|numpy)' \
    "$REPO/requirements.txt" | sha256sum | cut -c1-16)"
  [[ "$(cat "$TOOLS_STAMP" 2>/dev/null || echo "$tools_sum")" == "$tools_sum" ]] ||
    rm -f "$BUILD_STAMP"
  echo "$tools_sum" > "$TOOLS_STAMP"
fi

# 4. The colcon build of ros_ws.
build_sum="$(fingerprint sgim_msgs sgim_nodes sim_bridge teacher)"
if [[ $FORCE == 1 || "$(cat "$BUILD_STAMP" 2>/dev/null)" != "$build_sum" ]]; then
  say "building the ROS 2 workspace in $WS"
  (
    cd "$WS"
    export PATH="$VENV/bin:$PATH" VIRTUAL_ENV="$VENV"
    export CMAKE_PREFIX_PATH="$VENV" AMENT_PREFIX_PATH="$VENV"
    # The venv prefix is not a colcon workspace; colcon's warning about it is harmless.
    colcon --log-level error build --symlink-install \
      --event-handlers console_cohesion- status- summary+ \
      --cmake-args -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$VENV/bin/python" \
      >"$WS/build.log" 2>&1 ||
      { tail -n 40 "$WS/build.log" >&2; die "colcon build failed; full log in $WS/build.log"; }
  )
  echo "$build_sum" > "$BUILD_STAMP"
  say "workspace built"
fi

# 5. Our modules' bytecode. Python reads cached bytecode even where PYTHONDONTWRITEBYTECODE
# (set on some machines) stops it from writing any: without this step every node process
# compiled our modules again at each start, about 60 ms of CPU per node (up to date: 0.2 s).
(cd "$REPO" && "$VENV/bin/python" -m compileall -q -j 0 sgim_nodes/sgim_nodes \
  sim_bridge/sim_bridge teacher/teacher sgim_msgs/sgim_ros >/dev/null) || say "warning: could not compile the bytecode"
say "ready: source ros_ws/env.sh to use the workspace in a shell"
