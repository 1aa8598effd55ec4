"""Render layers (alpha, AOVs) from Python: the same values as the command."""

import json
import subprocess

import numpy as np
import pytest

import niebla


def test_python_layers_equal_the_command_line_layers(tiny_scene, tmp_path, niebla_bin):
    tiny_scene["render"]["integrator"] = {"type": "volpath"}
    tiny_scene["shapes"].append({"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90}, "bsdf": {"type": "diffuse"}})
    file = tmp_path / "tiny.json"
    file.write_text(json.dumps(tiny_scene))
    out = tmp_path / "cli.exr"
    subprocess.run(
        [niebla_bin, "render", str(file), "--aovs", "all", "--spp", "4", "--seed", "3", "--quiet", "-o", str(out)],
        check=True,
        capture_output=True,
    )
    layers = niebla.Scene.from_dict(tiny_scene).render_layers("all", spp=4, seed=3, threads=2, progress=False)
    cli = niebla.read_exr_layers(out)
    names = ["beauty", "alpha", "direct", "indirect", "emission", "surface", "albedo", "normal", "depth", "variance"]
    assert sorted(layers) == sorted(cli) == sorted(names)
    for name in names:
        assert layers[name].dtype == np.float32
        assert np.array_equal(layers[name].view(np.uint32), cli[name].view(np.uint32)), name
    assert layers["alpha"].shape == (30, 40) and layers["normal"].shape == (30, 40, 3)
    split = layers["direct"] + layers["indirect"] + layers["emission"] + layers["surface"]
    assert np.allclose(split, layers["beauty"], rtol=1e-5, atol=1e-7)


def test_unknown_layers_and_integrators_without_them_are_errors(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    with pytest.raises(ValueError, match='unknown layer "shade"'):
        scene.render_layers("albedo,shade", spp=1, progress=False)
    with pytest.raises(ValueError, match="only the volpath integrator"):
        scene.render_layers(["direct"], "single", spp=1, progress=False)
    assert scene.render_layers(["albedo"], "single", spp=1, progress=False)["albedo"].shape == (30, 40, 3)


def test_denoise_reduces_the_error_or_says_what_is_missing(tiny_scene):
    tiny_scene["render"]["integrator"] = {"type": "volpath"}
    scene = niebla.Scene.from_dict(tiny_scene)
    if niebla.oidn_library() is None:
        with pytest.raises(RuntimeError, match="pip install pyoidn"):
            niebla.denoise(np.zeros((2, 2, 3), np.float32))
        return
    reference = scene.render(spp=256, seed=1, progress=False)
    layers = scene.render_layers("albedo,normal", spp=4, seed=2, progress=False)
    denoised = niebla.denoise(layers["beauty"], albedo=layers["albedo"], normal=layers["normal"])
    assert denoised.shape == (30, 40, 3) and denoised.dtype == np.float32
    assert niebla.relative_mse(denoised, reference) < niebla.relative_mse(layers["beauty"], reference)
    with pytest.raises(ValueError, match="albedo"):
        niebla.denoise(layers["beauty"], albedo=layers["albedo"][:10])
