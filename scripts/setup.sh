#!/usr/bin/env bash
# Install what grainflow needs on Debian 12, idempotently and quietly when it is already there:
# Open MPI, parallel HDF5 (+ h5dump), libclang (bindgen), pkg-config, Mesa lavapipe (CPU Vulkan),
# ffmpeg (movies of the picture series; optional for users, tested in CI).
set -euo pipefail
PKGS=(libhdf5-openmpi-dev libopenmpi-dev openmpi-bin libclang-dev pkg-config mesa-vulkan-drivers libvulkan1 hdf5-tools ffmpeg)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust (https://rustup.rs)" >&2; exit 1; }
