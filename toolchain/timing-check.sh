#!/usr/bin/env bash
# The flake detector: runs the tests whose verdict depends on wall-clock scheduling (ctest
# label `timing`) again and again, alone or beside a busy process per CPU, and stops at the
# first failure. Use it before landing a change to any of them, or to anything they time.
#
#   toolchain/timing-check.sh [--repeat N] [--load] [-R REGEX] [--build-dir DIR] [-j N]
#
#   --repeat N     runs of each test (default 20); a test fails on its first failing run
#   --load         one busy process per CPU at normal priority for the whole check, as a
#                  build beside the tests would be (default: alone)
#   -R REGEX       only the timing tests whose names match
#   --build-dir    the configured native build (default build/); build it first
#   -j N           tests at once (default 1: each alone, as the claim is about the test)
# Exit status: ctest's (0 when every run of every selected test passed).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
repeat=20
load=0
regex=""
build_dir="$root/build"
jobs=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --repeat) repeat="$2"; shift ;;
    --load) load=1 ;;
    -R) regex="$2"; shift ;;
    --build-dir) build_dir="$2"; shift ;;
    -j) jobs="$2"; shift ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "timing-check.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
  shift
done
if [[ ! -f "$build_dir/CTestTestfile.cmake" ]]; then
  echo "timing-check.sh: no configured build in $build_dir (build it with cmake first)" >&2
  exit 2
fi

hogs=()
stop_hogs() { for pid in "${hogs[@]}"; do kill "$pid" 2>/dev/null || true; done; }
trap stop_hogs EXIT
if [[ "$load" == 1 ]]; then
  for _ in $(seq "$(nproc)"); do
    sh -c 'while :; do :; done' &
    hogs+=($!)
  done
  echo "timing-check: ${#hogs[@]} busy processes beside the tests"
fi
args=(--test-dir "$build_dir" -L timing --repeat "until-fail:$repeat" -j "$jobs" --output-on-failure)
[[ -n "$regex" ]] && args+=(-R "$regex")
echo "timing-check: every timing test up to $repeat times$([[ "$load" == 1 ]] && echo ' under load')"
start=$SECONDS
status=0
ctest "${args[@]}" || status=$?
echo "timing-check: $((SECONDS - start)) s, exit $status"
exit "$status"
