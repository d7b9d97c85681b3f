#!/usr/bin/env bash
# Installs every Debian package that rhot's build, tests, benchmarks and demo need.
# Idempotent: packages already present are left alone and only missing ones are fetched.
# Works as root on a fresh Debian 12 machine; as another user it asks sudo.
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git lld
  # the asan preset's compiler (CI's build): Clang 19 and its sanitizer runtimes. It builds the
  # tree in about half of GCC 12's time (docs/PERFORMANCE.md, "Build and test time")
  clang-19 libclang-rt-19-dev
  # core libraries
  nlohmann-json3-dev libspdlog-dev libfmt-dev libcli11-dev libglm-dev libeigen3-dev
  # tests and benchmarks; the format check (tests/CMakeLists.txt: layout.clang_format)
  libgtest-dev libgmock-dev libbenchmark-dev clang-format
  # tracking
  libopencv-dev libceres-dev
  # physics
  libbullet-dev
  # rendering: Vulkan loader and headers, Mesa's CPU driver (lavapipe), validation layer,
  # GLSL compiler, window system, assets, UI
  libvulkan-dev vulkan-tools mesa-vulkan-drivers vulkan-validationlayers glslc
  libglfw3-dev libtinygltf-dev libstb-dev libimgui-dev
  # headsets: the OpenXR loader and headers, and the core validation layer its tests turn on
  libopenxr-dev libopenxr-loader1 openxr-layer-corevalidation
  # a virtual display for window tests on machines without one
  xvfb xauth
  # camera nodes
  libzmq3-dev cppzmq-dev
  # streaming out: OSC (VMC protocol) and an independent receiver for its tests
  liblo-dev liblo-tools
)

if [[ ${EUID} -ne 0 ]]; then
  if command -v sudo >/dev/null; then SUDO=(sudo); else
    echo "setup-deps: run as root or install sudo" >&2; exit 1; fi
else
  SUDO=()
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "setup-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "setup-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" apt-get update -q
"${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup-deps: done"
