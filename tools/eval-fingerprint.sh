#!/usr/bin/env bash
# Runs every rhot-eval mode and the demo with fixed seeds and prints what they measured, timings
# removed, so two builds can be compared for identical behaviour:
#   tools/eval-fingerprint.sh build/release > before.txt   (on the old code)
#   tools/eval-fingerprint.sh build/release > after.txt    (on the new)
#   diff before.txt after.txt                               (no output: same figures)
# Takes a few minutes in a release build.
set -euo pipefail
bin="${1:?usage: tools/eval-fingerprint.sh BUILD_DIR}"
cd "$(dirname "$0")/.."
assets=assets
tmp=$(mktemp -d)
trap 'rm -rf "${tmp}"' EXIT
# Drops every JSON member that is a time (…_ms, …_us, …_s of a measurement) or names the machine.
strip_timings() {
  python3 -c '
import json, sys
def clean(v):
    if isinstance(v, dict):
        return {k: clean(x) for k, x in v.items()
                if not (k.endswith(("_ms", "_us")) or "median" in k or "p99" in k or "p50" in k
                        or k in ("device", "cpu_device", "seconds", "wall_s", "stages", "frame"))}
    if isinstance(v, list):
        return [clean(x) for x in v]
    return v
print(json.dumps(clean(json.load(sys.stdin)), indent=1, sort_keys=True))'
}
run() {
  echo "== rhot-eval $*"
  "${bin}/rhot-eval" "$@" --json 2>/dev/null | strip_timings
}
run triangulation --rig ${assets}/rigs/seated-4.yaml --frames 200 --seed 1
run triangulation --rig ${assets}/rigs/room-8.yaml --frames 100 --seed 2 --dropout 0.1
run triangulation --rig ${assets}/rigs/stereo-2.yaml --frames 100 --seed 3
run wand --rig ${assets}/rigs/seated-4.yaml --length-mm 195 --frames 200 --seed 1
run stars --rig ${assets}/rigs/seated-4.yaml --set ${assets}/stars/seed-case.json --frames 1000 --seed 2
run hands --rig ${assets}/rigs/seated-4.yaml --motion all --frames 200 --seed 1
run hands --rig ${assets}/rigs/seated-4.yaml --layout ${assets}/hands/high-fidelity-right.json --motion fist --frames 100 --seed 1
run hands --rig ${assets}/rigs/seated-4.yaml --layout ${assets}/hands/low-cost-left.json --motion wave --frames 100 --seed 4 --filter
run grasp --scenario all
# The whole demo, headless: every frame's tracked hands and objects (the recording) must match.
for args in "--seed 1" "--seed 7 --sigma 0.5 --filter"; do
  echo "== rhot-demo --headless --frames 2400 ${args} (recording's digest)"
  "${bin}/rhot-demo" --headless --frames 2400 --eye 32x32 ${args} --record "${tmp}/rec.jsonl" --log-level off >/dev/null 2>&1
  sha256sum < "${tmp}/rec.jsonl"
done
