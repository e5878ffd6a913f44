# Sourced by the scripts: where mujoco-rs finds the MuJoCo 3.17.0 library at build and run time.
_ftfusion_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export MUJOCO_DYNAMIC_LINK_DIR="$_ftfusion_root/.deps/mujoco"
export LD_LIBRARY_PATH="$_ftfusion_root/.deps/mujoco${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export FTFUSION_MODELS="$_ftfusion_root/models_mjcf"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-2}"
# Mesa's Vulkan driver warns on every start without a runtime folder: give it one.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
  export XDG_RUNTIME_DIR="/tmp/ftfusion-runtime-$(id -u)"
  mkdir -p -m 700 "$XDG_RUNTIME_DIR"
fi
