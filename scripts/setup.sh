#!/usr/bin/env bash
# Installs everything ftfusion needs on a fresh Debian bookworm machine, idempotently:
# apt packages, the pinned Python packages, and the MuJoCo 3.17.0 shared library (taken
# from the official PyPI wheel) into .deps/mujoco/ for mujoco-rs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

apt_packages=(
  build-essential pkg-config git ca-certificates
  libclang-dev                                   # bindgen for fmi-sys
  mesa-vulkan-drivers libvulkan1                 # wgpu on Mesa lavapipe
  libegl1 libegl-mesa0 libgl1-mesa-dri libgles2  # headless MuJoCo rendering
  libfontconfig1-dev libfreetype-dev fonts-dejavu-core  # plot text
  libmujoco-dev                                  # MuJoCo 2.2.2: scene compatibility test
  libtbb12                                       # libcosimpy
)
missing=()
for p in "${apt_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing apt packages: ${missing[*]}"
  sudo_cmd=""; [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

python3 -m pip install -q --disable-pip-version-check -r "$root/scripts/requirements.txt"

mj="$root/.deps/mujoco"
if [ ! -f "$mj/libmujoco.so.3.17.0" ]; then
  pkg="$(python3 -c 'import mujoco, os; print(os.path.dirname(mujoco.__file__))')"
  mkdir -p "$mj"
  cp "$pkg/libmujoco.so.3.17.0" "$mj/"
fi
ln -sf libmujoco.so.3.17.0 "$mj/libmujoco.so"
echo "setup: done (MuJoCo library in $mj)"
