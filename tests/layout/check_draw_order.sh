#!/usr/bin/env bash
# Random draws in one call's arguments are made in an order the compiler picks: GCC and Clang pick
# differently, so `Eigen::Vector3d(u(rng), u(rng), u(rng))` builds another world (other noise,
# other test scenarios, other golden images) under each. Braces fix the order (left to right):
# `Eigen::Vector3d{u(rng), u(rng), u(rng)}`. This check fails on a call in parentheses with two or
# more draws from one generator on one line (a generator named rng, rng_, gen or engine).
#
#   check_draw_order.sh ROOT [FILE...]     (no FILE: every .cpp and .h under base engine tracking tools
#                                           tests, but the bad examples in tests/layout/data)
set -euo pipefail
root=$1
shift
cd "${root}"
files=("$@")
if [[ ${#files[@]} -eq 0 ]]; then
  mapfile -t files < <(git ls-files 'base/*.cpp' 'base/*.h' 'engine/*.cpp' 'engine/*.h' 'tracking/*.cpp' 'tracking/*.h' \
    'tools/*.cpp' 'tools/*.h' 'tests/*.cpp' 'tests/*.h' ':!tests/layout/data' 2>/dev/null || true)
fi
# Two draws directly inside one pair of parentheses (arguments of one call, or operands of one
# expression) are unordered; inside braces they are ordered.
bad=$(awk '
  FNR == 1 { depth = 0 }
  {
    delete count
    flagged = 0
    line = $0
    n = length(line)
    for (i = 1; i <= n; ++i) {
      c = substr(line, i, 1)
      rest = substr(line, i)
      if (match(rest, /^\((rng_?|gen|engine)\)/)) {
        if (depth > 0 && type[depth] == "(" && ++count[id[depth]] == 2 && !flagged++) print FILENAME ":" FNR ": " line
        i += RLENGTH - 1
        continue
      }
      if (c == "(" || c == "{" || c == "[") { ++depth; type[depth] = c; id[depth] = ++ids }
      else if ((c == ")" || c == "}" || c == "]") && depth > 0) --depth
    }
  }' "${files[@]}")
if [[ -n "${bad}" ]]; then
  echo "random draws in one pair of parentheses are made in an order the compiler picks (write the call with braces):" >&2
  echo "${bad}" >&2
  exit 1
fi
