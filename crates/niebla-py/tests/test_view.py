"""Scene.view(): the live viewer served from Python (the server of `niebla view`)."""

import json
import urllib.error
import urllib.request

import pytest

import niebla

SCENE = {
    "version": 1,
    "camera": {"type": "perspective", "position": [0, 0, 4], "target": [0, 0, 0], "width": 16, "height": 12},
    "render": {"integrator": {"type": "single"}, "spp": 4},
    "media": {"fog": {"sigma_a": 0.1, "sigma_s": 0.5}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}],
    "lights": [{"type": "constant", "radiance": 1}],
}


def test_view_serves_the_scene_and_stops(tmp_path):
    scene = niebla.Scene.from_dict(SCENE, base_dir=tmp_path)
    with scene.view(threads=1) as viewer:
        assert viewer.url.startswith("http://127.0.0.1:")
        page = urllib.request.urlopen(viewer.url, timeout=10).read().decode()
        assert "niebla view" in page
        state = json.loads(urllib.request.urlopen(viewer.url + "api/state", timeout=10).read())
        assert state["label"] == "<dict>"
        assert state["scene"]["media"]["fog"]["sigma_s"] == 0.5
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(viewer.url.rsplit("/t/", 1)[0] + "/t/" + "0" * 32 + "/api/state", timeout=10)
        assert refused.value.code == 403
        frame = urllib.request.urlopen(viewer.url + "api/frame?slot=0&after=0", timeout=60)
        assert frame.headers["X-Niebla-Width"] == "16"
        assert len(frame.read()) == 16 * 12 * 6
    assert not viewer.running
    with pytest.raises(urllib.error.URLError):
        urllib.request.urlopen(viewer.url, timeout=2)


def test_view_refuses_a_bad_host():
    scene = niebla.Scene.from_dict(SCENE)
    with pytest.raises(ValueError, match="host"):
        scene.view(host="not-an-address")
