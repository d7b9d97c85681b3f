#!/usr/bin/env bash
# Sets up (Debian packages), then configures, builds and runs every test in each preset named
# (default: asan, every test under AddressSanitizer and UndefinedBehaviorSanitizer; CI runs this).
# `tools/test.sh debug asan` runs the debug build's tests too.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup-deps.sh
presets=("$@")
[[ ${#presets[@]} -gt 0 ]] || presets=(asan)
for preset in "${presets[@]}"; do
  echo "== rhot: configure, build and test the '${preset}' preset"
  cmake --workflow --preset "${preset}"
done
