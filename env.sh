# Source this file (". ./env.sh") to use the qtree-tamp workspace built by scripts/setup.sh:
# activates the virtual environment, points the ament index at it, then overlays ros2_ws/install.
_qtree_root="$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")" && pwd)"
if [ ! -f "$_qtree_root/.venv/.qtree_setup_ok" ] || [ ! -f "$_qtree_root/ros2_ws/install/.qtree_build_ok" ]; then
  echo "qtree-tamp: the environment is not set up; run scripts/setup.sh first" >&2
  return 1 2>/dev/null || exit 1
fi
# shellcheck disable=SC1091
. "$_qtree_root/.venv/bin/activate"
export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
# setup.bash reads unset variables: relax nounset while sourcing it.
case $- in *u*) _qtree_u=1; set +u;; *) _qtree_u=0;; esac
# shellcheck disable=SC1091
. "$_qtree_root/ros2_ws/install/setup.bash"
[ "$_qtree_u" = 1 ] && set -u
export QTREE_ROOT="$_qtree_root"
export RCUTILS_COLORIZED_OUTPUT="${RCUTILS_COLORIZED_OUTPUT:-0}"
unset _qtree_root _qtree_u
