#!/usr/bin/env bash
# Regenerates every committed result in results/ with the commands the README
# quotes (release build; a few minutes on 2 cores, super-60m the longest).
# Times in the files differ from run to run; everything else is reproduced.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release
ringmesh=./target/release/ringmesh
for scene in small-hex realistic-26m paper-26m; do
    "$ringmesh" design "problems/$scene.toml" --relaxation anderson,paper,aitken
done
"$ringmesh" design problems/super-60m.toml
"$ringmesh" mesh problems/paper-26m.toml
"$ringmesh" front problems/paper-26m.toml
"$ringmesh" study problems/paper-26m.toml
"$ringmesh" study problems/realistic-26m.toml
