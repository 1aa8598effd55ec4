"""Scenes from files and dicts, their errors, and image files."""

import json
import subprocess

import numpy as np
import pytest

import niebla


def test_dict_and_file_scenes_render_identical_images(repo, tmp_path):
    path = repo / "scenes" / "smoke.json"
    desc = json.loads(path.read_text())
    desc["camera"]["width"], desc["camera"]["height"] = 90, 100
    file = tmp_path / "smoke_small.json"
    file.write_text(json.dumps(desc))
    from_file = niebla.Scene.from_file(file)
    from_dict = niebla.Scene.from_dict(desc, base_dir=tmp_path)
    a = from_file.render("volpath", spp=2, progress=False)
    b = from_dict.render("volpath", spp=2, progress=False)
    assert a.shape == (100, 90, 3) and a.dtype == np.float32
    assert a.mean() > 0
    assert np.array_equal(a, b)


def test_dict_scene_exposes_its_settings(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    assert (scene.width, scene.height, scene.spp, scene.seed) == (40, 30, 4, 1)
    assert scene.integrator == "single" and scene.media == ["fog"]
    assert scene.source == "<dict>"
    assert set(niebla.INTEGRATORS) >= {"emission", "single", "volpath"}


def test_to_dict_rebuilds_the_same_scene(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    density = np.random.default_rng(3).random((3, 4, 5)).astype(np.float32)
    scene.set_density("fog", density, bounds=((-1, 0, -1), (1, 2, 1)))
    again = niebla.Scene.from_dict(scene.to_dict())
    assert np.array_equal(scene.render(spp=1, progress=False), again.render(spp=1, progress=False))
    grid = scene.to_dict()["media"]["fog"]["density"]
    assert grid["type"] == "grid" and grid["dims"] == [5, 4, 3]
    assert np.array_equal(np.array(grid["data"], dtype=np.float32).reshape(3, 4, 5), density)


def test_numpy_values_inside_a_dict_are_accepted(tiny_scene):
    tiny_scene["lights"][0]["position"] = np.array([1.0, 3.0, 1.0])
    tiny_scene["lights"][0]["intensity"] = np.float32(10)
    tiny_scene["camera"]["width"] = np.int64(40)
    plain = niebla.Scene.from_dict(json.loads(json.dumps(tiny_scene, default=lambda v: v.tolist())))
    assert np.array_equal(
        niebla.Scene.from_dict(tiny_scene).render(spp=1, progress=False), plain.render(spp=1, progress=False)
    )


def test_scene_errors_are_value_errors_with_the_json_path(tiny_scene):
    tiny_scene["media"]["fog"]["sigma_s"] = [0.3, 0.35, -1]
    with pytest.raises(niebla.SceneError) as info:
        niebla.Scene.from_dict(tiny_scene)
    e = info.value
    assert isinstance(e, ValueError)
    assert e.file == "<dict>" and e.path == "media.fog.sigma_s[2]"
    assert str(e) == f"<dict>: media.fog.sigma_s[2]: {e.message}"
    assert "-1" in e.message


def test_file_errors_match_the_command_line(tiny_scene, tmp_path, niebla_bin):
    tiny_scene["media"]["fog"]["sigam_s"] = tiny_scene["media"]["fog"].pop("sigma_s")
    file = tmp_path / "typo.json"
    file.write_text(json.dumps(tiny_scene, indent=2))
    with pytest.raises(niebla.SceneError) as from_file:
        niebla.Scene.from_file(file)
    with pytest.raises(niebla.SceneError) as from_dict:
        niebla.Scene.from_dict(tiny_scene, name=str(file))
    assert from_file.value.path == "media.fog.sigam_s"
    assert str(from_file.value) == str(from_dict.value)
    cli = subprocess.run([niebla_bin, "info", str(file)], capture_output=True, text=True)
    assert cli.returncode != 0
    assert cli.stderr.strip() == f"error: {from_file.value}"


def test_unknown_medium_reference_names_the_shape(tiny_scene):
    tiny_scene["shapes"][0]["interior"] = "fgo"
    with pytest.raises(niebla.SceneError, match=r"^<dict>: shapes\[0\]\.interior: ") as info:
        niebla.Scene.from_dict(tiny_scene)
    assert info.value.path == "shapes[0].interior"


def test_non_finite_numbers_in_a_dict_name_their_path(tiny_scene):
    tiny_scene["lights"][0]["intensity"] = [1.0, float("nan"), 1.0]
    with pytest.raises(niebla.SceneError) as info:
        niebla.Scene.from_dict(tiny_scene)
    assert info.value.path == "lights[0].intensity[1]"
    assert "finite" in str(info.value)


def test_missing_file_and_bad_json_are_scene_errors(tmp_path):
    with pytest.raises(niebla.SceneError, match="cannot read scene file"):
        niebla.Scene.from_file(tmp_path / "nope.json")
    with pytest.raises(niebla.SceneError, match="invalid JSON"):
        niebla.Scene.from_json("{", name="broken")


def test_integrator_errors_name_the_render_integrator_path(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    with pytest.raises(niebla.SceneError) as info:
        scene.render({"type": "single", "sampling": "sideways"}, spp=1)
    assert info.value.path == "render.integrator.sampling"
    with pytest.raises(niebla.SceneError, match="render.integrator"):
        scene.render("photon-magic", spp=1)
    with pytest.raises(niebla.SceneError) as info:
        scene.render({"type": "volpath", "max_depth": -3}, spp=1)
    assert info.value.path.startswith("render.integrator.max_depth")


def test_render_arguments_are_checked(tiny_scene):
    scene = niebla.Scene.from_dict(tiny_scene)
    for kwargs in ({"spp": 0}, {"time": -1.0}, {"time": float("inf")}, {"threads": 0}, {"spp": 2, "time": 1.0}):
        with pytest.raises(ValueError):
            scene.render(progress=False, **kwargs)


def test_exr_round_trip_and_png(tiny_scene, tmp_path):
    image = niebla.Scene.from_dict(tiny_scene).render(progress=False)
    niebla.write_exr(image, tmp_path / "a.exr")
    assert np.array_equal(niebla.read_exr(tmp_path / "a.exr"), image)
    niebla.write_image(image.astype(np.float64), tmp_path / "b.exr")
    assert (tmp_path / "a.exr").read_bytes() == (tmp_path / "b.exr").read_bytes()
    niebla.write_png(image, tmp_path / "a.png", exposure=1.0)
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(OSError):
        niebla.write_exr(image, tmp_path / "missing" / "a.exr")
    with pytest.raises(ValueError):
        niebla.write_exr(image[..., :2], tmp_path / "c.exr")
    with pytest.raises(ValueError):
        niebla.write_image(image, tmp_path / "c.tiff")


def test_relative_mse_is_the_documented_formula():
    rng = np.random.default_rng(0)
    reference = rng.random((6, 5, 3)).astype(np.float32)
    image = (reference + rng.normal(0, 0.1, reference.shape)).astype(np.float32)
    eps = (0.01 * reference.astype(np.float64).mean()) ** 2
    expected = np.mean((image.astype(np.float64) - reference) ** 2 / (reference.astype(np.float64) ** 2 + eps))
    assert niebla.relative_mse(image, reference) == pytest.approx(expected, rel=1e-6)
    assert niebla.relative_mse(reference, reference) == 0.0
    with pytest.raises(ValueError):
        niebla.relative_mse(image, reference[:3])


def test_a_medium_nothing_refers_to_is_warned_about(tiny_scene):
    tiny_scene["media"]["smoke"] = {"sigma_a": 0.1, "sigma_s": 1.0}
    with pytest.warns(UserWarning, match=r'media\.smoke: medium "smoke" is not used') as record:
        niebla.Scene.from_dict(tiny_scene)
    assert len(record) == 1
    assert '"interior": "smoke"' in str(record[0].message)
    assert '"ambient_medium": "smoke"' in str(record[0].message)


def test_from_file_frame_applies_keyframes_and_frame_patterns(tiny_scene, tmp_path):
    desc = json.loads(json.dumps(tiny_scene))
    camera = desc["camera"]
    camera["keyframes"] = [{"frame": 1, "position": [0, 1, 4]}, {"frame": 5, "position": [4, 1, 0]}]
    desc["render"]["spp"] = 1
    file = tmp_path / "turn.json"
    file.write_text(json.dumps(desc))
    at3 = json.loads(niebla.Scene.from_file(file, frame=3).to_json())
    assert at3["camera"]["position"] == [2.0, 1.0, 2.0]
    assert "keyframes" not in at3["camera"]
    # The frame's scene renders as the same scene written out.
    alone = dict(desc, camera=dict(camera, position=[2.0, 1.0, 2.0]))
    del alone["camera"]["keyframes"]
    a = niebla.Scene.from_file(file, frame=3).render(spp=1, progress=False)
    b = niebla.Scene.from_dict(alone, base_dir=tmp_path).render(spp=1, progress=False)
    assert np.array_equal(a, b)
    # A file name with a frame pattern names the frame's file.
    desc["lights"] = [{"type": "envmap", "file": "sky.####.exr"}]
    file.write_text(json.dumps(desc))
    with pytest.raises(niebla.SceneError, match=r"lights\[0\]\.file.*sky\.0007\.exr"):
        niebla.Scene.from_file(file, frame=7)
