#!/usr/bin/env bash
# Sets up (Debian packages), then configures, builds and runs every test in each preset named
# (default: debug, then asan, which adds AddressSanitizer and UndefinedBehaviorSanitizer).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup-deps.sh
presets=("$@")
[[ ${#presets[@]} -gt 0 ]] || presets=(debug asan)
for preset in "${presets[@]}"; do
  echo "== rhot: configure, build and test the '${preset}' preset"
  cmake --workflow --preset "${preset}"
done
