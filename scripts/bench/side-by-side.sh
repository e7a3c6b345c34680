#!/usr/bin/env bash
# ringmesh's `lp` beside clarabel (QDLDL, faer) on the same plan LPs, and
# `gradient`, on the three net families of issue 38, in one run
# (benches/side_by_side.rs). Writes results/bench/side-by-side.csv and prints
# the table, the load before and after.
#
#   scripts/bench/side-by-side.sh                 # ~10³ and ~10⁴ free nodes
#   scripts/bench/side-by-side.sh 100000          # ~10⁵ (lp and clarabel; minutes a net)
#   scripts/bench/side-by-side.sh 1000,10000 out.csv
#
# The environment variables of benches/side_by_side.rs pass through
# (RINGMESH_SIDE_FAMILIES, RINGMESH_SIDE_REPEATS, RINGMESH_SIDE_GRADIENT,
# RINGMESH_SIDE_NETS: network files, e.g. `ringmesh mesh`'s network.json).
set -euo pipefail
cd "$(dirname "$0")/../.."
free="${1:-1000,10000}"
csv="${2:-results/bench/side-by-side.csv}"
mkdir -p "$(dirname "$csv")"
echo "load before: $(uptime)"
case "$csv" in /*) ;; *) csv="$PWD/$csv" ;; esac
RINGMESH_SIDE_FREE="$free" RINGMESH_SIDE_CSV="$csv" \
    cargo bench --bench side_by_side
echo "load after: $(uptime)"
