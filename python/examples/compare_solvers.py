"""Compare force-density strategies on paper-26m from Python, notebook style:
the design front (tension ratio against surface RMS, each solver's accuracy
knob swept), checked against the front the repository commits
(results/paper-26m/front.csv, made by `ringmesh front problems/paper-26m.toml
--solvers bisection,gradient,gradient-smooth,least-squares`) and plotted with
matplotlib.

    python python/examples/compare_solvers.py            # the committed front
    python python/examples/compare_solvers.py --points 3 --out /tmp/front.png

Then, in a notebook, change a knob and try again:

    net = scene.mesh()
    ringmesh.uniformity(net, "bisection", epsilon_n=0.5).ratio
"""

import argparse
import csv
import math
import sys
import time
from pathlib import Path

import ringmesh

ROOT = Path(__file__).resolve().parents[2]
SOLVERS = ["bisection", "gradient", "gradient-smooth", "least-squares"]


def committed_front(path: Path):
    with open(path, newline="") as f:
        return [
            {k: (v if k == "solver" else float(v)) for k, v in row.items()} for row in csv.DictReader(f)
        ]


def same_point(ours, theirs) -> bool:
    """Equal to the digits front.csv prints (11 significant for the ratio, 7
    for the knob and the RMS)."""

    def close(a, b, digits):
        return a == b or math.isclose(a, b, rel_tol=10.0 ** (1 - digits), abs_tol=1e-300)

    return (
        ours["solver"] == theirs["solver"]
        and close(ours["knob"], theirs["knob"], 7)
        and close(ours["ratio"], theirs["ratio"], 11)
        and close(ours["rms_mm"], theirs["rms_mm"], 7)
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=str(ROOT / "problems" / "paper-26m.toml"))
    parser.add_argument("--solvers", default=",".join(SOLVERS))
    parser.add_argument("--points", type=int, default=8)
    parser.add_argument("--committed", default=str(ROOT / "results" / "paper-26m" / "front.csv"))
    parser.add_argument("--out", default="front-python.png", help="the plot (PNG)")
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args()

    scene = ringmesh.Scene.from_toml(args.scene)
    clock = time.perf_counter()
    records = ringmesh.front(
        scene,
        args.solvers.split(","),
        args.points,
        progress=lambda p: print(
            f"  {p['solver']:>15} knob {p['knob']:.3e}: "
            + (f"ratio {p['ratio']:.6f}, RMS {p['rms_mm']:.3e} mm" if p["error"] is None else p["error"]),
            file=sys.stderr,
        ),
    )
    print(f"{scene.name}: {len(records)} points in {time.perf_counter() - clock:.1f} s")
    ok = [r for r in records if r["error"] is None]
    for r in records:
        if r["error"] is not None:
            print(f"  failed: {r['solver']} knob {r['knob']:.3e}: {r['error']}")

    status = 0
    committed = Path(args.committed)
    defaults = (
        args.scene == str(ROOT / "problems" / "paper-26m.toml")
        and args.solvers == ",".join(SOLVERS)
        and args.points == 8
    )
    if defaults and committed.is_file():
        theirs = committed_front(committed)
        matches = len(ok) == len(theirs) and all(map(same_point, ok, theirs))
        print(
            f"the committed front ({committed.relative_to(ROOT)}, {len(theirs)} points): "
            + ("reproduced" if matches else "NOT reproduced")
        )
        status = 0 if matches else 1

    if not args.no_plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4.5))
        for solver, marker in zip(SOLVERS + ["lp"], "osD^v"):
            pts = sorted((r["rms_mm"], r["ratio"]) for r in ok if r["solver"] == solver)
            if pts:
                x, y = zip(*pts)
                ax.plot(x, y, marker=marker, label=solver)
        ax.set_xscale("log")
        ax.set_xlabel("surface RMS of the forward solve (mm)")
        ax.set_ylabel("Tmax / Tmin")
        ax.set_title(f"{scene.name}: tension uniformity against surface accuracy")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.out, dpi=120)
        print(f"wrote {args.out}")
    return status


if __name__ == "__main__":
    sys.exit(main())
