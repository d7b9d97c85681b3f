#!/usr/bin/env bash
# The demo on camera nodes: builds the release preset, starts four rhot-node processes on
# loopback, each simulating one camera of the seated rig photographing the demo's world, and runs
# rhot-demo on them (--source nodes:...). Stops every node when the demo ends, however it ends.
# Arguments go to rhot-demo, e.g. tools/nodes-demo.sh --headless --frames 900 --stats stats.json
# RHOT_NODES_PORT: the first node's port (default 5601; node i publishes on 5601 + 2i, answers
# requests on the port after it).
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ "${RHOT_SKIP_SETUP:-0}" != 1 ]]; then
  tools/setup-deps.sh
  cmake --preset release
  cmake --build --preset release --target rhot-demo rhot-node
fi
port=${RHOT_NODES_PORT:-5601}
rig=assets/rigs/seated-4.yaml
scene=assets/scenes/default.json
# The simulated world's time 0, shared by the nodes: a second from now on the steady clock.
start=$(( $(build/release/rhot-node --print-clock) + 1000000000 ))
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT INT TERM
endpoints=()
for i in 0 1 2 3; do
  p=$((port + 2 * i))
  build/release/rhot-node --publish "tcp://127.0.0.1:$p" --node-id "$i" --sim-rig "$rig" --sim-camera "$i" --sim-scene "$scene" \
    --sim-start-ns "$start" >"build/release/rhot-node-$i.log" 2>&1 &
  pids+=($!)
  endpoints+=("tcp://127.0.0.1:$p")
done
echo "nodes-demo: four nodes on ports $port-$((port + 7)), logs in build/release/rhot-node-*.log"
sources=$(IFS=,; echo "${endpoints[*]}")
build/release/rhot-demo --rig "$rig" --scene "$scene" --source "nodes:$sources" "$@"
