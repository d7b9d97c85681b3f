#!/usr/bin/env bash
# Sets up (Debian packages), builds the release preset and runs the VR demo on its defaults.
# Arguments go to rhot-demo, e.g. tools/demo.sh --frames 900 --stats stats.json
set -euo pipefail
cd "$(dirname "$0")/.."
tools/setup-deps.sh
cmake --preset release
cmake --build --preset release --target rhot-demo
exec build/release/rhot-demo "$@"
