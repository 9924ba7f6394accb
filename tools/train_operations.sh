#!/bin/sh
# Rebuilds the shipped operation recognizer (docs/cobot/recognition.md, "Training"): builds
# sen3bot-sim, trains with the shipped settings (the defaults: 480 walks per operation, seed 1)
# into config/cobot/operations-model.yaml.gz, and rewrites the robot's reference routes at the
# end of config/cobot/operations.yaml (everything from its "# BEGIN references" line on).
# Run it from anywhere; extra arguments go to `sen3bot-sim train operations`.
#
#   tools/train_operations.sh [BUILD_DIR]       (default build-train, inside the repository)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-"$root/build-train"}
[ $# -gt 0 ] && shift

cmake -S "$root" -B "$build" -G Ninja >/dev/null
cmake --build "$build" --target sen3bot-sim
sim="$build/firmware/sen3bot-sim"

cd "$root"
operations=config/cobot/operations.yaml
model=config/cobot/operations-model.yaml.gz
references=$(mktemp)
trap 'rm -f "$references"' EXIT

"$sim" train operations --operations "$operations" --references "$references"
# Keep the hand-written part, then the generated block.
kept=$(mktemp)
sed '/^# BEGIN references/,$d' "$operations" > "$kept"
cat "$kept" "$references" > "$operations"
rm -f "$kept"

"$sim" train operations --operations "$operations" --out "$model" "$@"
