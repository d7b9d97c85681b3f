#!/usr/bin/env bash
# Where a build's time went, from ninja's own log: the costliest compile steps and the sum per
# target (seconds of wall time per step; with N jobs on fewer cores each step's time is inflated
# alike, so read the ranking and the shares, and `time` the whole build for the total).
#
#   tools/build-times.sh [BUILD_DIR] [N]     (default build/asan, 25 rows)
set -euo pipefail
build=${1:-build/asan}
rows=${2:-25}
log="${build}/.ninja_log"
[[ -f "${log}" ]] || { echo "build-times: ${log} not found (build first)" >&2; exit 1; }
# .ninja_log v5: start_ms end_ms mtime output hash; a rebuilt output appears again (keep the last).
steps=$(awk 'NR > 1 && $4 ~ /\.o$/ { t[$4] = ($2 - $1) / 1000.0 } END { for (o in t) printf "%.1f %s\n", t[o], o }' "${log}")
total=$(awk '{ s += $1 } END { printf "%.0f", s }' <<<"${steps}")
echo "compile steps: ${total} s in all"
echo
echo "slowest steps:"
sort -rn <<<"${steps}" | head -n "${rows}" | awk '{ printf "%8.1f s  %s\n", $1, $2 }'
echo
echo "per target (steps):"
awk -v total="${total}" '{ g = $2; sub(/\.dir\/.*/, "", g); sub(/.*CMakeFiles\//, "", g); s[g] += $1; n[g]++ }
  END { for (g in s) printf "%.1f %.1f %s %d\n", s[g], 100 * s[g] / total, g, n[g] }' <<<"${steps}" |
  sort -rn | head -n "${rows}" | awk '{ printf "%8.1f s  %5.1f %%  %s (%d)\n", $1, $2, $3, $4 }'
