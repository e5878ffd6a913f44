#!/usr/bin/env bash
# Installs everything ftfusion needs on a fresh Debian bookworm machine, idempotently:
# apt packages, the pinned Python packages, zig (PyPI package ziglang) and cargo-zigbuild
# (cargo xtask fmu links the FMU against glibc 2.17 with them), and the MuJoCo 3.17.0
# shared library (taken from the official PyPI wheel) into .deps/mujoco/ for mujoco-rs.
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
  valgrind                                       # scripts/memcheck.sh
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

# ziglang: the zig toolchain that cargo-zigbuild finds as `python3 -m ziglang` (0.14: with
# zig 0.15+, cargo-zigbuild warns that bindgen may need clang 18; bookworm's libclang is 14).
python3 -m pip install -q --disable-pip-version-check -r "$root/scripts/requirements.txt" \
  "ziglang==0.14.1"

# cargo-zigbuild: `cargo xtask fmu` builds the FMU for x86_64-unknown-linux-gnu.2.17, so that
# it loads wherever glibc 2.17 or newer is (manylinux2014: RHEL/Rocky 8, Ubuntu 20.04).
zigbuild_version=0.24.1
if [ "$(cargo-zigbuild --version 2>/dev/null)" != "cargo-zigbuild $zigbuild_version" ]; then
  echo "setup: installing cargo-zigbuild $zigbuild_version (cargo install, a few minutes)"
  cargo install --quiet --locked cargo-zigbuild --version "$zigbuild_version"
fi

mj="$root/.deps/mujoco"
if [ ! -f "$mj/libmujoco.so.3.17.0" ]; then
  pkg="$(python3 -c 'import mujoco, os; print(os.path.dirname(mujoco.__file__))')"
  mkdir -p "$mj"
  cp "$pkg/libmujoco.so.3.17.0" "$mj/"
fi
ln -sf libmujoco.so.3.17.0 "$mj/libmujoco.so"
echo "setup: done (MuJoCo library in $mj)"
