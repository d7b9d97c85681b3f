#!/usr/bin/env bash
# The demo on camera nodes: builds the release preset, starts four rhot-node processes on
# loopback, each simulating one camera of the seated rig photographing the demo's world, and runs
# rhot-demo on them (--source nodes:...). Stops every node when the demo ends, however it ends.
#
#   tools/nodes-demo.sh [--logs DIR] [rhot-demo's arguments...]
#   e.g. tools/nodes-demo.sh --headless --frames 900 --stats stats.json
#
# --logs DIR: the nodes' logs (rhot-node-0.log ... rhot-node-3.log) go into DIR, created if
#   missing; without it, into a new temporary folder (under $TMPDIR, else /tmp), named when the
#   nodes start. Every other argument goes to rhot-demo.
# RHOT_SKIP_SETUP=1: skip the setup and the build. Without it the script first runs
#   tools/setup-deps.sh, which installs the Debian packages rhot needs (as root, or with sudo),
#   then configures and builds the release preset's rhot-demo and rhot-node; with it,
#   build/release/rhot-demo and build/release/rhot-node must be built already.
# Keys: the script makes a key pair for the master and each node in LOGS/keys (rhot-node keygen),
#   gives each side the other's public certificate, and runs everything with CURVE security
#   (docs/camera-nodes.md, "Security").
# RHOT_NODES_PORT: the first node's port (default 5601; node i publishes on 5601 + 2i, answers
#   requests on the port after it).
set -euo pipefail

logs=""
demo_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --logs)
      [[ $# -ge 2 ]] || { echo "nodes-demo: --logs needs a folder: --logs DIR" >&2; exit 1; }
      logs=$2
      shift 2
      ;;
    --logs=*)
      logs=${1#--logs=}
      shift
      ;;
    *)
      demo_args+=("$1")
      shift
      ;;
  esac
done
if [[ -n "$logs" ]]; then
  mkdir -p -- "$logs"
  logs=$(cd -- "$logs" && pwd)  # absolute: the script moves to the repository's root next
else
  logs=$(mktemp -d "${TMPDIR:-/tmp}/rhot-nodes-demo.XXXXXX")
fi

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
keys=$logs/keys
[[ -f "$keys/master/master.key_secret" ]] || build/release/rhot-node keygen --out "$keys/master" --name master >/dev/null
mkdir -p "$keys/master/trusted"
for i in 0 1 2 3; do
  [[ -f "$keys/node$i/node$i.key_secret" ]] || build/release/rhot-node keygen --out "$keys/node$i" --name "node$i" >/dev/null
  mkdir -p "$keys/node$i/trusted"
  cp "$keys/master/master.key" "$keys/node$i/trusted/"
  cp "$keys/node$i/node$i.key" "$keys/master/trusted/"
done
endpoints=()
for i in 0 1 2 3; do
  p=$((port + 2 * i))
  build/release/rhot-node --publish "tcp://127.0.0.1:$p" --node-id "$i" --sim-rig "$rig" --sim-camera "$i" --sim-scene "$scene" \
    --sim-start-ns "$start" --keys "$keys/node$i" >"$logs/rhot-node-$i.log" 2>&1 &
  pids+=($!)
  endpoints+=("node$i@tcp://127.0.0.1:$p")
done
echo "nodes-demo: four nodes on ports $port-$((port + 7)), logs in $logs/rhot-node-*.log"
sources=$(IFS=,; echo "${endpoints[*]}")
build/release/rhot-demo --rig "$rig" --scene "$scene" --source "nodes:$sources" --keys "$keys/master" "${demo_args[@]}"
