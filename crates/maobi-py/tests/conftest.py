"""Shared fixtures: the repository, the `maobi` binary the numbers are checked against, and
that binary's outputs for the inputs the tests give the Python API too."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def _maobi_bin():
    """The CLI built by this checkout (`cargo build -p maobi` or the test step), or $MAOBI_BIN."""
    env = os.environ.get("MAOBI_BIN")
    if env:
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        p = target / profile / "maobi"
        if p.exists():
            return p
    return None


@pytest.fixture(scope="session")
def cli():
    """Runs the `maobi` binary; returns its stdout. Skips (saying why) when it is not built,
    unless MAOBI_REQUIRE_CLI=1 (as in .ci/run), where that fails."""
    exe = _maobi_bin()
    if exe is None or not exe.exists():
        msg = "the maobi binary is not built (cargo build -p maobi): the comparisons with the CLI are skipped"
        if os.environ.get("MAOBI_REQUIRE_CLI") == "1":
            pytest.fail(msg)
        pytest.skip(msg)

    def run(*args, cwd=None):
        r = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=600)
        assert r.returncode == 0, f"maobi {' '.join(map(str, args))} failed: {r.stderr}"
        return r.stdout

    return run


@pytest.fixture(scope="session")
def written_yong(cli, tmp_path_factory):
    """`maobi write 永 --size 128 -o DIR`: the folder."""
    out = tmp_path_factory.mktemp("cli") / "yong"
    cli("write", "永", "--size", "128", "-o", out)
    return out


def load_json(path):
    return json.loads(Path(path).read_text(encoding="utf-8"))


def without_timing(report):
    """A report.json without its wall times (which differ from run to run)."""
    r = json.loads(json.dumps(report))
    r.pop("timing_ms", None)
    if isinstance(r.get("refine"), dict):
        r["refine"].pop("time_ms", None)
    return r
