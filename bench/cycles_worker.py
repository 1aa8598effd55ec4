"""A Blender Cycles renderer driven over stdin/stdout by bench/peers.py's
`Cycles` (for bench/compare.py, fire_cycles.py and production_frame.py; run
with bench/.venv-cycles/bin/python, where `bpy` 5.0.1 is installed).

    cycles_worker.py SCENE.json SCENE_DIR THREADS

builds the scene once (bench/niebla2cycles.py), prints one JSON line
{"ready": true, "build_s": ...} (or {"unsupported": "why"}), then for each
request line {"spp": N, "seed": S, "out": "x.exr", "width": W, "height": H}
renders and answers {"seconds": T, "cpu_seconds": C}: the wall time of the
render call alone and the CPU seconds (user + system, time.process_time,
as getrusage(RUSAGE_SELF)) of the process (all threads) during it
(scene building, Blender start and the EXR write excluded; the per-call volume
octree build that Cycles does is included, and measured separately by
requesting a 1x1-pixel, 1-spp render). width/height override the film size
(to measure that fixed cost).
"""

import contextlib
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def main():
    scene_path, scene_dir, threads = sys.argv[1], sys.argv[2], int(sys.argv[3])
    import bpy
    import niebla2cycles

    with open(scene_path) as f:
        desc = json.load(f)
    t0 = time.perf_counter()
    try:
        with contextlib.redirect_stdout(sys.stderr):
            scene = niebla2cycles.build(desc, scene_dir, threads)
    except niebla2cycles.Unsupported as e:
        print(json.dumps({"unsupported": str(e)}), flush=True)
        return
    print(json.dumps({"ready": True, "build_s": time.perf_counter() - t0}), flush=True)
    w0, h0 = scene.render.resolution_x, scene.render.resolution_y
    for line in sys.stdin:
        req = json.loads(line)
        scene.cycles.samples = int(req["spp"])
        scene.cycles.seed = int(req["seed"])
        scene.render.resolution_x = int(req.get("width", w0))
        scene.render.resolution_y = int(req.get("height", h0))
        scene.render.filepath = req["out"]
        with contextlib.redirect_stdout(sys.stderr):
            t0, c0 = time.perf_counter(), time.process_time()
            bpy.ops.render.render(write_still=False)
            t, cpu = time.perf_counter() - t0, time.process_time() - c0
            img = bpy.data.images["Render Result"]
            img.save_render(req["out"])
        print(json.dumps({"seconds": t, "cpu_seconds": cpu}), flush=True)


if __name__ == "__main__":
    main()
