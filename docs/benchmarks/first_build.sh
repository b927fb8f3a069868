#!/usr/bin/env bash
# A user's first experience: the README's two commands on a fresh clone, timed one after the
# other (the main job's build first, the tests sharing what it built), in a target folder of
# the clone's own. Writes docs/benchmarks/first_build.json, which the README quotes
# (tests/it/figures.rs holds it to this file). About 20 minutes on 2 cores; outside CI.
#
#   docs/benchmarks/first_build.sh            # clones this checkout's HEAD into a temporary folder
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git clone --quiet "$root" "$work/clone"
cd "$work/clone"
main='cargo run --release -p generator -- models/cart_pendulum.ron -o target/cart_pendulum.rs'
tests='cargo test --workspace --release'
grep -qF "$main" README.md && grep -qF "$tests" README.md || { echo "the README's commands changed: edit this script" >&2; exit 1; }
seconds() {
    local start end
    start=$(date +%s%N)
    "$@" >"$work/log" 2>&1 || { tail -50 "$work/log" >&2; exit 1; }
    end=$(date +%s%N)
    awk -v ns=$((end - start)) 'BEGIN { printf "%.1f", ns / 1e9 }'
}
main_s=$(seconds bash -c "$main")
tests_s=$(seconds bash -c "$tests")
commit=$(git rev-parse HEAD)
cat >"$root/docs/benchmarks/first_build.json.tmp" <<JSON
{
  "command": "docs/benchmarks/first_build.sh",
  "commit": "$commit",
  "cores": $(nproc),
  "main_job": "$main",
  "main_job_seconds": $main_s,
  "tests": "$tests",
  "tests_seconds": $tests_s
}
JSON
mv "$root/docs/benchmarks/first_build.json.tmp" "$root/docs/benchmarks/first_build.json"
echo "first build: main job ${main_s} s, then the tests ${tests_s} s"
