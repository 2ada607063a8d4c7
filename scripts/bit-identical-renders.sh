#!/usr/bin/env bash
# Renders every built-in scene and every scene file with every method on the CPU backend, as
# EXR with every AOV, with two `refract` binaries, and compares the files byte for byte: the
# check that a refactoring or an optimisation changed no bit (docs/performance.md).
#
# Usage: scripts/bit-identical-renders.sh BEFORE_BINARY AFTER_BINARY [RES]
# Run from the repository root (the scene files read ../shared/data). Exits 1 on a difference.
set -euo pipefail
before=$1; after=$2; res=${3:-160}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
methods=$("$before" methods 2>/dev/null | awk 'NF && $1 !~ /^(backends:|--param|reference)/ && $0 !~ /^ / {print $1}' | sort -u)
scenes=$("$before" scenes 2>/dev/null | awk 'NF {print $1}')
render_all() {
    local bin=$1 out=$2
    mkdir -p "$out"
    for scene in $scenes scenes/*.toml; do
        for method in $methods; do
            # Methods that decline a scene (a conductor for the glass-only families) write
            # nothing, in both builds alike.
            "$bin" render "$scene" --method "$method" --backend cpu --res "$res" \
                --out "$out/$(basename "$scene" .toml)-$method.exr" > /dev/null 2>&1 || true
        done
    done
}
render_all "$before" "$work/before"
render_all "$after" "$work/after"
count=$(ls "$work/before" | wc -l)
if diff -r -q "$work/before" "$work/after"; then
    echo "$count renders byte-identical"
else
    echo "renders differ (of $count)" >&2
    exit 1
fi
