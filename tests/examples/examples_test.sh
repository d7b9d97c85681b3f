#!/usr/bin/env bash
# The example applications of tools/examples against the installed package: installs this build
# into a fresh prefix, configures and builds each example there as an outside project would
# (find_package(rhot) and nothing of the source tree), runs both and checks what they print.
#
#   examples_test.sh BUILD_DIR SOURCE_DIR CXX_COMPILER
set -euo pipefail
build_dir=$1
source_dir=$2
cxx=$3
work=$(mktemp -d "${TMPDIR:-/tmp}/rhot-examples.XXXXXX")
trap 'rm -rf "${work}"' EXIT

echo "== install into ${work}/prefix"
cmake --install "${build_dir}" --prefix "${work}/prefix" >"${work}/install.log"
# Nothing of the source or build tree may be needed: the package must stand alone.
if grep -rqs -e "${source_dir}/" -e "${build_dir}/" "${work}/prefix/lib/cmake/rhot"; then
  echo "examples_test: the installed package names the source or build tree:" >&2
  grep -rn -e "${source_dir}/" -e "${build_dir}/" "${work}/prefix/lib/cmake/rhot" >&2
  exit 1
fi
test -f "${work}/prefix/include/rhot/engine/launch/Launch.h"
test ! -e "${work}/prefix/include/rhot/engine/render/vk"
test -f "${work}/prefix/share/rhot/assets/scenes/default.json"
# The module that holds OpenCV's image files and capture (tracking/media/Media.h), where the
# applications' run path finds it.
test -f "${work}/prefix/lib/rhot/librhot_media.so"

# The linker is the user's choice; this build's (lld where there is one, as cmake/RhotOptions.cmake
# picks) links the two examples in a second instead of ld.bfd's several.
linker=()
if command -v ld.lld >/dev/null; then linker=(-DCMAKE_EXE_LINKER_FLAGS=-fuse-ld=lld); fi

# Both examples in one configure: a parent project of the user's that adds each example's own,
# unchanged CMakeLists.txt (compiler checks and finding rhot's dependencies were 6 s of each
# configure, under the sanitizers). Each still finds the package for itself.
cat >"${work}/CMakeLists.txt" <<'PARENT'
cmake_minimum_required(VERSION 3.25)
project(rhot_examples LANGUAGES CXX)
add_subdirectory(track)
add_subdirectory(headless)
PARENT
for example in track headless; do cp -r "${source_dir}/tools/examples/${example}" "${work}/${example}"; done
echo "== configure and build tools/examples/track and tools/examples/headless"
cmake -S "${work}" -B "${work}/build" -G Ninja -DCMAKE_CXX_COMPILER="${cxx}" \
  -DCMAKE_PREFIX_PATH="${work}/prefix" "${linker[@]}" >"${work}/configure.log" || { cat "${work}/configure.log"; exit 1; }
cmake --build "${work}/build" || exit 1

for program in build/track/track_example build/headless/headless_example; do
  # Read whole first: grep -q stops at the first match, and under pipefail readelf's broken pipe
  # would fail the check.
  dynamic=$(readelf -d "${work}/${program}")
  grep -q "path: \[.*${work}/prefix/lib/rhot" <<<"${dynamic}" || {
    echo "examples_test: ${program} has no run path to the installed media module:" >&2; grep -i path <<<"${dynamic}" >&2; exit 1; }
done

echo "== track_example"
"${work}/build/track/track_example" --seconds 2 | tee "${work}/track.out"
tip_mm=$(sed -n 's/^index fingertips: \([0-9.]*\) mm from the truth.*/\1/p' "${work}/track.out")
[[ -n "${tip_mm}" ]] || { echo "examples_test: track_example printed no fingertip error" >&2; exit 1; }
grep -q 'right wrist (' "${work}/track.out" || { echo "examples_test: track_example printed no tracked right wrist" >&2; exit 1; }
grep -q 'star [0-9]* at (' "${work}/track.out" || { echo "examples_test: track_example printed no tracked object" >&2; exit 1; }
# Measured 1.20 mm over these 2 s (seated-4, seed 1, deterministic; 0.82 mm in an earlier tracker): a tracker that doubles it fails.
awk -v e="${tip_mm}" 'BEGIN { exit !(e < 2.0) }' || { echo "examples_test: fingertips ${tip_mm} mm from the truth" >&2; exit 1; }

echo "== headless_example"
"${work}/build/headless/headless_example" --frames 270 --png "${work}/left.png" | tee "${work}/headless.out"
grep -Eq '^ran 270 frames .* the right hand was tracked in [1-9][0-9]*$' "${work}/headless.out" || {
  echo "examples_test: headless_example did not run 270 frames with the right hand tracked" >&2; exit 1; }
grep -q 'the right index fingertip came within' "${work}/headless.out"
test -s "${work}/left.png"
echo "examples_test: both examples built against the installed package and ran"
