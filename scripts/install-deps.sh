#!/usr/bin/env bash
# Installs the Debian 12 packages sphfem needs to build, test and render. Idempotent: it
# installs only what is missing and prints nothing when everything is already there.
# `--fuzz` adds what the readers' libFuzzer targets need (`make fuzz`, fuzz/README.md).
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev zlib1g-dev
  libassimp-dev libtet1.5-dev libeigen3-dev
  # Rendering: EGL (headless, surfaceless platform) and OpenGL through Mesa's llvmpipe,
  # libepoxy to load GL entry points, GLFW for `sphfem view`, ffmpeg for MP4 videos.
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libepoxy-dev libglfw3-dev ffmpeg
  # The Python module (pybind11), its tests and the plotting example.
  python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib
)
if [ "${1:-}" = "--fuzz" ]; then
  # The readers' libFuzzer targets: clang, its libFuzzer and OpenMP runtime.
  packages+=(clang libclang-rt-14-dev libomp-dev)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
    echo "install-deps: missing packages: ${missing[*]}; run this script as root or install them" >&2
    exit 1
  fi
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
