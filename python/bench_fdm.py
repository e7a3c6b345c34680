"""Python overhead of `ringmesh.fdm` on a 10⁵-node net against the CLI (a
bench, not a test: it prints times and asserts nothing).

    python python/bench_fdm.py [--side 317] [--repeats 5]

Three numbers, medians of the repeats, for the same net (a square grid, its
border fixed):
* `solve`: the library's forward solve alone (`Equilibrium.solve_s`, timed in
  Rust around `fdm::solve_network`);
* `valid.`: the library's validation of the network (`validate_s`), which
  the CLI does as well when it reads the file;
* `python`: the whole `ringmesh.fdm(net)` call: arrays in (one copy), the
  network validated, the solve, arrays out (no copy);
* `cli`: `ringmesh fdm net.json -o eq.json`, the process with its JSON in and
  out.
The overhead the issue bounds (≤ 10 %) is (python − solve) / solve; the
boundary's own share is (python − validation − solve) / solve.
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
# The installed package, not the source folder beside this script (which has
# no native module); the test helpers for the net.
sys.path = [p for p in sys.path if Path(p or ".").resolve() != HERE]
sys.path.insert(0, str(HERE / "tests"))

import ringmesh  # noqa: E402
from test_arrays import grid_net  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--side", type=int, default=317)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    net = grid_net(args.side)
    print(f"grid {args.side}×{args.side}: {net.n_nodes} nodes, {net.n_edges} cables")
    python, solve, library = [], [], []
    for _ in range(args.repeats):
        clock = time.perf_counter()
        eq = ringmesh.fdm(net)
        python.append(time.perf_counter() - clock)
        solve.append(eq.solve_s)
        library.append(eq.validate_s + eq.solve_s)
    exe = os.environ.get("RINGMESH_CLI", str(ROOT / "target" / "release" / "ringmesh"))
    cli = []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "net.json"
        path.write_text(net.to_json())
        for _ in range(args.repeats):
            clock = time.perf_counter()
            subprocess.run([exe, "fdm", str(path), "-o", str(Path(tmp) / "eq.json")], check=True, capture_output=True)
            cli.append(time.perf_counter() - clock)
    s, lib, p, c = (statistics.median(v) for v in (solve, library, python, cli))
    print(f"solve  {s:.3f} s (library, timed in Rust)")
    print(f"valid. {lib - s:.3f} s (the library's network validation, which the CLI does too)")
    print(
        f"python {p:.3f} s (ringmesh.fdm: {100 * (p - s) / s:+.1f} % of the solve; "
        f"the boundary alone, arrays in and out: {100 * (p - lib) / s:+.1f} %)"
    )
    print(f"cli    {c:.3f} s (ringmesh fdm with its JSON in and out: {100 * (c - s) / s:+.1f} %)")


if __name__ == "__main__":
    main()
