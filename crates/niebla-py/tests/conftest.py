"""Shared fixtures of the Python tests of the niebla bindings."""

import copy
import os
import shutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]

# A small scene that renders in milliseconds: a fog sphere under a point light
# and a sky, single scattering with MIS.
TINY_SCENE = {
    "version": 1,
    "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 40, "height": 30},
    "render": {"integrator": {"type": "single", "sampling": "mis"}, "spp": 4, "seed": 1},
    "media": {"fog": {"sigma_a": 0.05, "sigma_s": [0.3, 0.35, 0.4], "phase": {"type": "hg", "g": 0.3}}},
    "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}],
    "lights": [{"type": "point", "position": [1, 3, 1], "intensity": 10}, {"type": "constant", "radiance": 0.1}],
}


@pytest.fixture
def tiny_scene():
    """A fresh copy of the tiny scene dict."""
    return copy.deepcopy(TINY_SCENE)


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def niebla_bin():
    """The `niebla` command: $NIEBLA_BIN (scripts/test.sh sets it), else a
    build in target/. Tests that compare with the command are skipped when
    there is none, unless $NIEBLA_BIN is set (then a missing file fails)."""
    given = os.environ.get("NIEBLA_BIN")
    if given:
        assert Path(given).is_file(), f"NIEBLA_BIN={given} does not exist"
        return given
    for profile in ("release", "debug"):
        candidate = REPO / "target" / profile / "niebla"
        if candidate.is_file():
            return str(candidate)
    found = shutil.which("niebla")
    if found:
        return found
    pytest.skip("no niebla binary (build it with `cargo build --release -p niebla-cli` or set NIEBLA_BIN)")
