#!/usr/bin/env bash
# Set up qtree-tamp on a machine with no system ROS: a virtual environment with ROS 2 Jazzy from
# PyPI wheels and every pinned dependency, then a colcon build of ros2_ws into ros2_ws/install.
#
# Idempotent: a second run with nothing changed finishes in seconds. Each stage writes its stamp
# only after it succeeded, so a failed or interrupted run is never mistaken for a good one.
#
# Usage: scripts/setup.sh            (PYTHON=/path/to/python3.11+ to choose the interpreter)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
VENV_STAMP="$VENV/.qtree_setup_ok"
BUILD_STAMP="$ROOT/ros2_ws/install/.qtree_build_ok"
PYTHON="${PYTHON:-python3}"

say() { printf '\033[1m[setup]\033[0m %s\n' "$*"; }
die() { printf '\033[1;31m[setup] error:\033[0m %s\n' "$*" >&2; exit 1; }

# --- 1. prerequisites -------------------------------------------------------------------------
command -v "$PYTHON" >/dev/null 2>&1 || die "'$PYTHON' not found: install Python 3.11 or newer"
"$PYTHON" - <<'PY' || die "Python 3.11 or newer is required (found $("$PYTHON" --version 2>&1)); set PYTHON=..."
import sys
sys.exit(0 if sys.version_info >= (3, 11) else 1)
PY
"$PYTHON" -c 'import venv, ensurepip' 2>/dev/null \
  || die "the venv module is missing: on Debian/Ubuntu run 'apt-get install python3-venv'"
"$PYTHON" - <<'PY' || die "Python headers (Python.h) are missing: on Debian/Ubuntu run 'apt-get install python3-dev'"
import os, sys, sysconfig
sys.exit(0 if os.path.exists(os.path.join(sysconfig.get_paths()['include'], 'Python.h')) else 1)
PY
missing=()
for tool in cmake make gcc g++; do command -v "$tool" >/dev/null 2>&1 || missing+=("$tool"); done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    say "installing build tools (${missing[*]}) with apt-get"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq cmake make gcc g++ \
      || die "apt-get could not install cmake make gcc g++"
  else
    die "missing build tools: ${missing[*]} (on Debian/Ubuntu: sudo apt-get install cmake make gcc g++)"
  fi
fi

# --- 2. virtual environment with pinned dependencies ----------------------------------------------
want_venv="$(cat "$ROOT/requirements.in" "$ROOT/constraints.txt" "$ROOT/scripts/fix_wheel_cmake.py" \
  | sha256sum | cut -d' ' -f1)"
if [ -f "$VENV_STAMP" ] && [ "$(cat "$VENV_STAMP")" = "$want_venv" ] && [ -x "$VENV/bin/python" ]; then
  say "virtual environment up to date ($VENV)"
else
  rm -f "$VENV_STAMP" "$BUILD_STAMP"
  if [ ! -x "$VENV/bin/python" ]; then
    say "creating virtual environment in $VENV"
    rm -rf "$VENV"
    "$PYTHON" -m venv "$VENV" || die "could not create the virtual environment"
  fi
  say "installing pinned dependencies (ROS 2 Jazzy wheels, pin, fcl, numba, mcap, rerun, ...)"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --upgrade 'pip>=24' \
    || die "could not upgrade pip"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    -r "$ROOT/requirements.in" -c "$ROOT/constraints.txt" \
    || die "pip could not install the dependencies (see the messages above)"
  "$VENV/bin/python" "$ROOT/scripts/fix_wheel_cmake.py" "$VENV" \
    || die "could not rewrite the message wheels' exported CMake include paths"
  echo "$want_venv" > "$VENV_STAMP"
fi

# --- 3. colcon build of the workspace ------------------------------------------------------------
want_build="$( (cd "$ROOT/ros2_ws/src" && find . -type f \( -name '*.msg' -o -name '*.srv' \
  -o -name '*.action' -o -name 'CMakeLists.txt' -o -name 'package.xml' -o -name 'setup.py' \
  -o -name 'setup.cfg' -o -path '*/resources/*' -o -path '*/urdf/*' -o -path '*/scenarios/*' \) -print0 | sort -z | xargs -0 sha256sum; \
  cat "$VENV_STAMP") | sha256sum | cut -d' ' -f1)"
if [ -f "$BUILD_STAMP" ] && [ "$(cat "$BUILD_STAMP")" = "$want_build" ]; then
  say "workspace up to date (ros2_ws/install)"
else
  rm -f "$BUILD_STAMP"
  say "building ros2_ws with colcon (about 30 s)"
  (
    # shellcheck disable=SC1091
    . "$VENV/bin/activate"
    export AMENT_PREFIX_PATH="$VIRTUAL_ENV"
    cd "$ROOT/ros2_ws"
    colcon --log-base log build --symlink-install --event-handlers console_cohesion+ \
      --cmake-args -DBUILD_TESTING=OFF > "$ROOT/ros2_ws/build.log" 2>&1
  ) || { tail -40 "$ROOT/ros2_ws/build.log" >&2; die "colcon build failed (full log: ros2_ws/build.log)"; }
  echo "$want_build" > "$BUILD_STAMP"
fi

# --- 4. compiled kernels -------------------------------------------------------------------------
# numba compiles the motion planner's hot-path kernels once (about 10 s) and caches them beside
# the source; done here so that no node start or test pays for it.
say "compiling the motion planner's kernels (numba, cached)"
( cd "$ROOT" && . ./env.sh >/dev/null && python -c "import stpik_motion_planner.kernels" ) \
  || die "could not compile stpik_motion_planner/kernels.py (numba)"
say "done. Use it with:  . ./env.sh"
