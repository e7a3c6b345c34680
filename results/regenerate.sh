#!/usr/bin/env bash
# Regenerates every committed result in results/ with the commands the README
# quotes (release build; a few minutes on 2 cores, super-60m the longest).
# Times in the files differ from run to run; everything else is reproduced.
# Every command names its folder with -o: without it a command writes under
# runs/ (git-ignored), never here.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release
ringmesh=./target/release/ringmesh
for scene in small-hex realistic-26m paper-26m; do
    "$ringmesh" design "problems/$scene.toml" --relaxation anderson,paper,aitken -o "results/$scene"
done
"$ringmesh" design problems/super-60m.toml -o results/super-60m
"$ringmesh" mesh problems/paper-26m.toml -o results/paper-26m
"$ringmesh" front problems/paper-26m.toml --solvers bisection,gradient,gradient-smooth,least-squares -o results/paper-26m
"$ringmesh" study problems/paper-26m.toml -o results/paper-26m
"$ringmesh" study problems/realistic-26m.toml -o results/realistic-26m
# The tube of paper-26m sized for a margin of 2, from the shipped catalogue
# (sizing.csv, paper-26m-sized.toml), and the aperture study at the paper's
# F/D (0.154) and at a shallow one (realistic-26m, 0.6): results/<scene>/apertures/.
"$ringmesh" size problems/paper-26m.toml --margin 2 --sections problems/carbon-tubes.csv -o results/paper-26m
"$ringmesh" apertures problems/paper-26m.toml --apertures 26,40,60,80,100 -o results/paper-26m/apertures
"$ringmesh" apertures problems/realistic-26m.toml --apertures 26,40,60,80,100 -o results/realistic-26m/apertures
# The error budget of the three reference dishes (their [effects.thermal] and
# [tolerances]): the flexible-truss design and the conventional one, each built
# on the same flexible truss (results/<scene>/budget/, budget-conventional/).
for scene in realistic-26m paper-26m super-60m; do
    "$ringmesh" budget "problems/$scene.toml" -o "results/$scene/budget"
    "$ringmesh" budget "problems/$scene.toml" --conventional -o "results/$scene/budget-conventional"
done
