"""Densities from numpy arrays and VDB files: axis order and placement."""

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

import niebla

WIDTH = HEIGHT = 64
FOV_Y = 30.0
CAMERA_Z = 5.0


def glowing_box_scene(to_world=None):
    """An emissive, weakly absorbing grid medium seen straight down -z by a
    camera at (0.5, 0.5, 5) looking at the box's center; no lights, so the
    image shows the density's emission alone."""
    medium = {
        "type": "grid",
        "density": {"type": "constant", "value": 0},
        "sigma_a": 0.01,
        "sigma_s": 0,
        "emission": {"L_ve": 1.0},
    }
    if to_world is not None:
        medium["to_world"] = to_world
    return {
        "version": 1,
        "camera": {
            "type": "perspective",
            "position": [0.5, 0.5, CAMERA_Z],
            "target": [0.5, 0.5, 0.5],
            "up": [0, 1, 0],
            "fov_y": FOV_Y,
            "width": WIDTH,
            "height": HEIGHT,
        },
        "render": {"integrator": {"type": "emission"}, "spp": 16},
        "media": {"glow": medium},
        "ambient_medium": "glow",
    }


def project(point):
    """Continuous pixel coordinates (column, row) of a world point: row 0 at
    the top, columns increasing to the camera's right (+x here)."""
    x, y, z = point
    depth = CAMERA_Z - z
    tan_half = math.tan(math.radians(FOV_Y) / 2)
    column = WIDTH / 2 + (x - 0.5) / (depth * tan_half) * HEIGHT / 2
    row = HEIGHT / 2 - (y - 0.5) / (depth * tan_half) * HEIGHT / 2
    return column, row


def centroid(image):
    luminance = image.astype(np.float64).mean(axis=2)
    rows, columns = np.indices(luminance.shape) + 0.5
    total = luminance.sum()
    assert total > 0
    return (columns * luminance).sum() / total, (rows * luminance).sum() / total


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_single_bright_voxel_lands_where_expected(dtype):
    # Distinct sizes per axis, so a swapped axis cannot pass: (nz, ny, nx).
    nz, ny, nx = 5, 6, 8
    i, j, k = 6, 1, 3  # x, y, z indices of the bright voxel
    density = np.zeros((nz, ny, nx), dtype=dtype)
    density[k, j, i] = 1.0
    scene = niebla.Scene.from_dict(glowing_box_scene())
    scene.set_density("glow", density, bounds=((0, 0, 0), (1, 1, 1)))
    image = scene.render(spp=16, progress=False)
    center = ((i + 0.5) / nx, (j + 0.5) / ny, (k + 0.5) / nz)
    expected = project(center)
    found = centroid(image)
    # The glow is the trilinear tent around the cell center, two cells wide.
    assert abs(found[0] - expected[0]) < 0.75 and abs(found[1] - expected[1]) < 0.75, (found, expected)
    # Large x is to the right, small y is toward the bottom of the image.
    assert found[0] > WIDTH / 2 and found[1] > HEIGHT / 2


def test_bounds_and_to_world_place_the_array():
    density = np.zeros((4, 4, 4), dtype=np.float32)
    density[1, 2, 1] = 1.0
    lo, hi = (0.2, 0.1, 0.0), (0.6, 0.9, 0.8)
    shift = [0.1, -0.05, 0.0]
    scene = niebla.Scene.from_dict(glowing_box_scene(to_world={"translate": shift}))
    scene.set_density("glow", density, bounds=(lo, hi))
    image = scene.render(spp=16, progress=False)
    local = [lo[a] + (idx + 0.5) * (hi[a] - lo[a]) / 4 for a, idx in enumerate((1, 2, 1))]
    expected = project([local[a] + shift[a] for a in range(3)])
    found = centroid(image)
    assert abs(found[0] - expected[0]) < 0.75 and abs(found[1] - expected[1]) < 0.75, (found, expected)


def test_array_views_and_dtypes_give_the_same_image():
    rng = np.random.default_rng(7)
    density = rng.random((6, 5, 4))
    scene = niebla.Scene.from_dict(glowing_box_scene())
    scene.set_density("glow", np.ascontiguousarray(density, dtype=np.float32))
    a = scene.render(spp=2, progress=False)
    # The same values through a non-contiguous, transposed view.
    scene.set_density("glow", np.ascontiguousarray(density.transpose(2, 1, 0)).transpose(2, 1, 0))
    b = scene.render(spp=2, progress=False)
    assert np.array_equal(a, b)


def test_a_homogeneous_medium_takes_an_array_density(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    homogeneous = scene.render(spp=2, progress=False)
    scene.set_density("fog", np.ones((2, 2, 2)), bounds=((-1, 0, -1), (1, 2, 1)))
    ones = scene.render(spp=2, progress=False)
    scene.set_density("fog", np.zeros((2, 2, 2)), bounds=((-1, 0, -1), (1, 2, 1)))
    empty = scene.render(spp=2, progress=False)
    assert scene.to_dict()["media"]["fog"]["type"] == "grid"
    # A unit density over the sphere's box is the homogeneous medium again
    # (up to the estimators); an empty one leaves only the sky.
    assert abs(ones.mean() - homogeneous.mean()) < 0.05 * homogeneous.mean()
    assert empty.mean() < homogeneous.mean()


def test_bad_densities_raise_and_leave_the_scene_unchanged(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    before = scene.render(spp=1, progress=False)
    bad = np.ones((2, 3, 4))
    bad[1, 2, 3] = -1.0
    with pytest.raises(niebla.SceneError) as info:
        scene.set_density("fog", bad)
    assert info.value.path.startswith("media.fog.density")
    with pytest.raises(niebla.SceneError, match=r"^<dict>: media\.smoke: unknown medium \"smoke\"; known media: fog"):
        scene.set_density("smoke", np.ones((2, 2, 2)))
    with pytest.raises(niebla.SceneError) as info:
        scene.set_density("fog", np.ones((2, 2, 2)), bounds=((0, 0, 0), (1, -1, 1)))
    assert info.value.path.startswith("media.fog.density.bounds")
    with pytest.raises(ValueError):
        scene.set_density("fog", np.ones((2, 2)))
    with pytest.raises(ValueError):
        scene.set_density("fog", np.ones((0, 2, 2)))
    assert np.array_equal(scene.render(spp=1, progress=False), before)
    with pytest.raises(niebla.SceneError) as info:
        scene.set_density_vdb("fog", "/nonexistent/cloud.vdb")
    assert info.value.path == "media.fog.density.file"


def python_with_openvdb():
    for python in ("/usr/bin/python3",):
        if Path(python).exists():
            ok = subprocess.run([python, "-c", "import pyopenvdb"], capture_output=True).returncode == 0
            if ok:
                return python
    return None


def test_a_vdb_density_matches_the_same_array(tmp_path):
    python = python_with_openvdb()
    if python is None:
        pytest.skip("Debian's python3-openvdb is not installed (scripts/test.sh installs it)")
    density = np.zeros((4, 4, 4), dtype=np.float32)
    density[1, 2, 3] = 1.0
    file = tmp_path / "voxel.vdb"
    # One active voxel at index (x, y, z) = (3, 2, 1), voxel size 1/4 with the
    # index points shifted to the cell centers of the unit box.
    script = (
        "import pyopenvdb as vdb\n"
        "g = vdb.FloatGrid()\n"
        "g.name = 'density'\n"
        "g.getAccessor().setValueOn((3, 2, 1), 1.0)\n"
        "g.transform = vdb.createLinearTransform([[0.25, 0, 0, 0], [0, 0.25, 0, 0], [0, 0, 0.25, 0],"
        " [0.125, 0.125, 0.125, 1]])\n"
        f"vdb.write({str(file)!r}, grids=[g])\n"
    )
    subprocess.run([python, "-c", script], check=True)
    from_vdb = niebla.Scene.from_dict(glowing_box_scene())
    from_vdb.set_density_vdb("glow", file)
    from_array = niebla.Scene.from_dict(glowing_box_scene())
    from_array.set_density("glow", density)
    a = from_vdb.render(spp=16, progress=False)
    b = from_array.render(spp=16, progress=False)
    ca, cb = centroid(a), centroid(b)
    assert abs(ca[0] - cb[0]) < 0.5 and abs(ca[1] - cb[1]) < 0.5, (ca, cb)
