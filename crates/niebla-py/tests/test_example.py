"""The notebook-style example runs (small settings, no window)."""

import subprocess
import sys


def test_smoke_from_numpy_example_runs_and_writes_its_images(repo, tmp_path):
    script = repo / "examples" / "smoke_from_numpy.py"
    out = tmp_path / "out"
    args = ["--spp", "1", "--size", "24", "--voxels", "16", "--out", str(out), "--no-show"]
    result = subprocess.run([sys.executable, str(script)] + args, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "multiple scattering adds" in result.stdout
    for name in ("volpath.exr", "single.exr", "difference.exr", "volpath.png"):
        assert (out / name).is_file()
