"""Compares the tables of two ringmesh runs: every CSV file of the first
folder must exist in the second with the same rows, column for column, but
time_s (the only value that differs from run to run). Exit 1 on a difference."""
import csv
import pathlib
import sys


def table(path):
    lines = [l for l in path.read_text().splitlines() if not l.startswith("#")]
    rows = list(csv.reader(lines))
    keep = [i for i, name in enumerate(rows[0]) if name != "time_s"]
    return [[row[i] for i in keep] for row in rows]


whole, sharded = map(pathlib.Path, sys.argv[1:3])
names = sorted(p.name for p in whole.glob("*.csv"))
if not names:
    sys.exit(f"compare: no table in {whole}")
for name in names:
    if not (sharded / name).exists():
        sys.exit(f"compare: the merged run has no {name}")
    a, b = table(whole / name), table(sharded / name)
    if a != b:
        diff = next(i for i, (x, y) in enumerate(zip(a + [[]], b + [[]])) if x != y)
        sys.exit(f"compare: {name} differs at row {diff}: {a[diff:diff+1]} vs {b[diff:diff+1]}")
    print(f"compare: {name}: {len(a) - 1} rows equal to the unsharded run")
