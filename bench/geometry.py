#!/usr/bin/env python3
"""Rays per second of niebla's mesh hierarchy next to Mitsuba 3's (Embree).

Runs `niebla bench geometry --export DIR` (meshes written as binary PLY, the
rays as raw little-endian float32 origin/direction sextuples), loads each
mesh into a Mitsuba 3 scene, traces the same rays with `scene.ray_intersect`
(closest hit with Mitsuba's full surface record), with
`scene.ray_intersect_preliminary` (closest hit: distance, primitive and
barycentrics only, what niebla's figure measures) and `scene.ray_test` (any
hit) in one wavefront call each, and
prints both renderers' rays per second at the same thread count, with a
check that they hit the same rays (count of hits and sum of distances).

Set up Mitsuba first: `bash bench/setup.sh` (bench/.venv). Then:

    bench/.venv/bin/python bench/geometry.py --threads 2 --levels 5,6,7,8,9

Mitsuba's llvm_ad_rgb variant compiles its kernels on the first call; every
timing here is of a second call with the same sizes (compiled kernels cached).
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--niebla", default=os.path.join(root, "target", "release", "niebla"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--levels", default="5,6,7,8,9")
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()

    sys.path.insert(0, here)
    from llvm import use_newest_llvm

    use_newest_llvm()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)

    with tempfile.TemporaryDirectory() as tmp:
        cmd = [args.niebla, "bench", "geometry", "--levels", args.levels, "--rays", str(args.rays),
               "--threads", str(args.threads), "--export", tmp]
        print("$", " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True)
        print()
        print(f"Mitsuba {mi.__version__} ({args.variant}, {args.threads} threads) on the same meshes and rays:")
        print(f"{'triangles':>10} {'load s':>8} {'kind':>8} {'niebla Mray/s':>14} {'mitsuba full':>13} "
              f"{'ratio':>6} {'mitsuba prelim':>15} {'ratio':>6} {'niebla any':>11} {'mitsuba any':>12} "
              f"{'ratio':>6} {'hits n/m':>18}")
        for level in args.levels.split(","):
            stats = dict(line.split() for line in open(os.path.join(tmp, f"niebla_{level}.txt")))
            t0 = time.perf_counter()
            scene = mi.load_dict({"type": "scene",
                                  "mesh": {"type": "ply", "filename": os.path.join(tmp, f"mesh_{level}.ply")}})
            load = time.perf_counter() - t0
            for kind in ("primary", "random"):
                r = np.fromfile(os.path.join(tmp, f"{kind}_{level}.f32"), dtype="<f4").reshape(-1, 6)
                rays = mi.Ray3f(mi.Point3f(r[:, 0], r[:, 1], r[:, 2]), mi.Vector3f(r[:, 3], r[:, 4], r[:, 5]))
                dr.eval(rays)

                def closest():
                    si = scene.ray_intersect(rays)
                    valid = si.is_valid()
                    t = dr.select(valid, si.t, 0.0)
                    dr.eval(valid, t)
                    return valid, t

                def preliminary():
                    pi = scene.ray_intersect_preliminary(rays)
                    dr.eval(pi.t, pi.prim_index)
                    return pi

                def anyhit():
                    hit = scene.ray_test(rays)
                    dr.eval(hit)
                    return hit

                closest()
                preliminary()
                anyhit()  # compile once
                t0 = time.perf_counter()
                valid, t = closest()
                dr.sync_thread()
                tc = time.perf_counter() - t0
                t0 = time.perf_counter()
                preliminary()
                dr.sync_thread()
                tp = time.perf_counter() - t0
                t0 = time.perf_counter()
                anyhit()
                dr.sync_thread()
                ta = time.perf_counter() - t0
                n = r.shape[0]
                m_closest, m_prelim, m_any = n / tc, n / tp, n / ta
                n_closest, n_any = float(stats[f"{kind}_closest"]), float(stats[f"{kind}_any"])
                m_hits = int(np.array(valid).sum())
                n_hits = int(stats[f"{kind}_hits"])
                m_tsum = float(np.array(t, dtype=np.float64).sum())
                n_tsum = float(stats[f"{kind}_tsum"])
                print(f"{int(stats['triangles']):>10} {load:>8.2f} {kind:>8} {n_closest / 1e6:>14.2f} "
                      f"{m_closest / 1e6:>13.2f} {n_closest / m_closest:>6.2f} {m_prelim / 1e6:>15.2f} "
                      f"{n_closest / m_prelim:>6.2f} {n_any / 1e6:>11.2f} "
                      f"{m_any / 1e6:>12.2f} {n_any / m_any:>6.2f} {n_hits:>9}/{m_hits:<8}")
                if abs(n_hits - m_hits) > 1e-4 * n or abs(n_tsum - m_tsum) > 1e-4 * max(abs(m_tsum), 1.0):
                    print(f"  warning: the renderers disagree: hits {n_hits} vs {m_hits}, "
                          f"sum of t {n_tsum:.6g} vs {m_tsum:.6g}", file=sys.stderr)


if __name__ == "__main__":
    main()
