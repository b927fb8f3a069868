#!/bin/sh
# rustc time per generated module, compiled alone as a library at opt-level 3 (against the seam
# crate, its one dependency, built first).
# Usage: sh generated/compile-times.sh   (from the repository root)
set -e
out=$(mktemp -d)
rustc --edition 2024 --crate-type rlib --crate-name seam -C opt-level=3 --out-dir "$out" runtime/seam/src/lib.rs
for f in generated/src/*.rs; do
    case "$f" in */lib.rs|*/registry.rs) continue ;; esac
    start=$(date +%s.%N)
    rustc --edition 2024 --crate-type lib -C opt-level=3 -D warnings --extern seam="$out/libseam.rlib" --out-dir "$out" "$f"
    end=$(date +%s.%N)
    printf '%-40s %6d lines %6.2f s\n' "$f" "$(wc -l < "$f")" "$(echo "$end - $start" | bc)"
done
rm -rf "$out"
