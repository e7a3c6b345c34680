"""Every result from Python equals the CLI's for the same input, bit for bit:
the nets, the forward solve, the uniformity design and the whole design run
on small-hex and paper-26m."""

import csv

import numpy as np
import pytest

import ringmesh
from conftest import PROBLEMS, read_json

SCENES = ["small-hex", "paper-26m"]


def untimed(value):
    """A report's value without its wall times (which differ run to run)."""
    if isinstance(value, dict):
        return {k: untimed(v) for k, v in value.items() if not k.endswith("time_s")}
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return value


@pytest.mark.parametrize("name", SCENES)
def test_mesh_writes_the_clis_network_json_byte_for_byte(name, meshes):
    net = ringmesh.Scene.from_toml(PROBLEMS / f"{name}.toml").mesh()
    text = meshes[name].read_text(encoding="utf-8")
    assert net.to_json() == text
    back = ringmesh.Network.from_json(meshes[name])
    for field in ("positions", "edges", "fixed", "q"):
        assert np.array_equal(getattr(back, field), getattr(net, field)), field
    assert list(back.groups) == list(net.groups)
    assert net.positions.shape == (net.n_nodes, 3) and net.positions.dtype == np.float64
    assert net.edges.shape == (net.n_edges, 2) and net.edges.dtype == np.int64
    assert net.facets.shape[1] == 3 and net.facets.max() < net.n_nodes


@pytest.mark.parametrize("name", SCENES)
def test_fdm_equals_the_cli_bit_for_bit(name, meshes, cli, tmp_path):
    out = tmp_path / "eq.json"
    cli("fdm", meshes[name], "-o", out)
    expected = read_json(out)
    eq = ringmesh.fdm(ringmesh.Network.from_json(meshes[name]))
    assert np.array_equal(eq.positions, np.array(expected["nodes"]))
    assert np.array_equal(eq.lengths, np.array(expected["lengths"]))
    assert np.array_equal(eq.forces, np.array(expected["forces"]))
    assert np.array_equal(eq.reactions, np.array(expected["reactions"]))
    assert eq.max_residual == expected["max_residual"]


@pytest.mark.parametrize("name", SCENES)
def test_uniformity_equals_the_cli_bit_for_bit(name, meshes, cli, tmp_path):
    out = tmp_path / "u.json"
    cli("uniformity", meshes[name], "-o", out)
    expected = read_json(out)
    d = ringmesh.uniformity(ringmesh.Network.from_json(meshes[name]))
    assert d.termination == expected["termination"] == "converged"
    assert d.solver == expected["solver"]
    assert np.array_equal(d.q, np.array(expected["q"]))
    assert np.array_equal(d.tensions, np.array(expected["tensions"]))
    assert d.ratio == expected["ratio"]
    assert d.max_residual == expected["max_residual"]


def test_uniformity_with_a_solver_and_its_setting_equals_the_cli_default(meshes, cli, tmp_path):
    """bisection's ε set by keyword to its default gives the CLI's design."""
    out = tmp_path / "u.json"
    cli("uniformity", meshes["small-hex"], "--solver", "bisection", "-o", out)
    expected = read_json(out)
    d = ringmesh.uniformity(
        ringmesh.Network.from_json(meshes["small-hex"]), "bisection", epsilon_n=0.0
    )
    assert np.array_equal(d.q, np.array(expected["q"]))
    assert d.ratio == expected["ratio"]


@pytest.mark.parametrize("name", SCENES)
def test_design_equals_the_cli_bit_for_bit(name, cli, tmp_path):
    cli("design", PROBLEMS / f"{name}.toml", "-o", tmp_path)
    expected = read_json(tmp_path / "design.json")
    seen = []
    r = ringmesh.design(ringmesh.Scene.from_toml(PROBLEMS / f"{name}.toml"), progress=seen.append)
    assert r.termination == expected["termination"] == "converged"
    assert r.ratio == expected["ratio"]
    assert r.outer_iterations == expected["outer_iterations"]
    net = expected["net"]
    assert np.array_equal(r.q, np.array(net["q"]))
    assert np.array_equal(r.tensions, np.array(net["tensions_n"]))
    assert np.array_equal(r.positions, np.array(net["nodes_xyz_m"]))
    assert r.assembled_positions.shape == r.positions.shape
    # The report is design.json's content, up to the wall times.
    for key in ("net", "verification", "conventional", "surface", "boundary_m", "limit_margin"):
        assert untimed(r.report[key]) == untimed(expected[key]), key
    # One progress record per outer iteration of the design's loop.
    assert [s["iteration"] for s in seen] == [h["iteration"] for h in expected["history"]]
    assert all(s["relaxation"] == "anderson" for s in seen)
    # Cut lengths: cables.csv prints 13 significant digits.
    with open(tmp_path / "cables.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    cut = np.array([float(row["cut_length_m"]) for row in rows])
    assert len(cut) == len(r.cut_lengths)
    assert np.allclose(r.cut_lengths, cut, rtol=1e-12, atol=0)
    assert np.all(r.cut_lengths < r.lengths)


def test_front_records_equal_the_clis_front_csv(cli, tmp_path):
    cli("front", PROBLEMS / "small-hex.toml", "--points", "3", "-o", tmp_path)
    with open(tmp_path / "front.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    seen = []
    records = ringmesh.front(
        ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml"), points=3, progress=seen.append
    )
    ok = [r for r in records if r["error"] is None]
    assert len(ok) == len(rows) > 0
    for r, row in zip(ok, rows):
        assert r["solver"] == row["solver"]
        # front.csv prints 11 significant digits of the ratio, 7 of the rest.
        assert r["ratio"] == pytest.approx(float(row["ratio"]), rel=1e-10)
        assert r["knob"] == pytest.approx(float(row["knob"]), rel=1e-6, abs=1e-12)
        assert r["rms_mm"] == pytest.approx(float(row["rms_mm"]), rel=1e-6, abs=1e-12)
    # Progress came from the solving threads while the call had released the
    # GIL (holding it, the first callback would have deadlocked).
    assert sorted((s["solver"], s["knob"]) for s in seen) == sorted(
        (r["solver"], r["knob"]) for r in records
    )


def test_study_records_equal_the_clis_table(cli, tmp_path):
    cli(
        "study", PROBLEMS / "small-hex.toml", "--knobs", "tolerance", "--tolerances", "1e-3",
        "-o", tmp_path,
    )
    with open(tmp_path / "accuracy-vs-time.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    seen = []
    records = ringmesh.study(
        ringmesh.Scene.from_toml(PROBLEMS / "small-hex.toml"),
        knobs="tolerance",
        tolerances_m=[1e-3],
        progress=seen.append,
    )
    assert len(records) == len(rows) == 2  # the reference and the one point
    assert len(seen) == len(records)
    for r, row in zip(records, rows):
        assert r["error"] is None and row["error"] == ""
        assert (r["knob"], r["settings.tolerance_m"]) == (row["knob"], float(row["tolerance_m"]))
        assert r["summary.outer_iterations"] == int(row["outer_iterations"])
        # accuracy-vs-time.csv prints 11 significant digits of the ratios, 7 of the rest.
        assert r["ratio"] == pytest.approx(float(row["ratio"]), rel=1e-10)
        assert r["built_ratio"] == pytest.approx(float(row["built_ratio"]), rel=1e-10)
        assert r["rms_mm"] == pytest.approx(float(row["rms_mm"]), rel=1e-6)
