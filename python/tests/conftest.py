"""Shared fixtures: where the repository and the shared maps are, and how to run host-sim."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"


@pytest.fixture
def shared_maps():
    """`../shared/maps` beside the repository, or a skip that says so in the output."""
    maps = SHARED / "maps"
    if not maps.is_dir():
        pytest.skip(f"{maps} is absent: the shared reference maps are test data kept beside the repository")
    return maps


@pytest.fixture(scope="session")
def host_sim():
    """A function running `host-sim` (the repository's, built by cargo if need be)."""
    exe = os.environ.get("HOST_SIM")

    def call(*args):
        cmd = [exe, *args] if exe else ["cargo", "run", "--release", "-q", "-p", "host-sim", "--", *args]
        out = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        return out.stdout

    return call
