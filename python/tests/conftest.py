"""Shared fixtures: the repository's scenes and the CLI built from the same
crate (``target/release/ringmesh``, or ``$RINGMESH_CLI``), whose outputs the
Python results must equal bit for bit."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PROBLEMS = ROOT / "problems"


def cli_path() -> Path:
    return Path(os.environ.get("RINGMESH_CLI", ROOT / "target" / "release" / "ringmesh"))


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI with arguments; returns its completed process (it must
    succeed)."""
    exe = cli_path()
    assert exe.is_file(), f"the CLI {exe} is not built: run `cargo build --release` first"

    def run(*args):
        done = subprocess.run(
            [str(exe), *map(str, args)], cwd=ROOT, capture_output=True, text=True
        )
        assert done.returncode == 0, f"ringmesh {' '.join(map(str, args))}: {done.stderr}"
        return done

    return run


@pytest.fixture(scope="session")
def meshes(cli, tmp_path_factory):
    """`ringmesh mesh` of small-hex and paper-26m: scene name → network.json path."""
    out = {}
    for name in ("small-hex", "paper-26m"):
        folder = tmp_path_factory.mktemp(f"mesh-{name}")
        cli("mesh", PROBLEMS / f"{name}.toml", "-o", folder)
        out[name] = folder / "network.json"
    return out


def read_json(path: Path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)
