#!/usr/bin/env python3
"""The production frame: a generated sparse cloud VDB (~500^3 voxels,
written at bench time by OpenVDB's reference library through
bench/make_big_vdb.py) under a sun and a sky, over a diffuse floor, rendered
at 1920x1080 with `volpath` by niebla, Blender Cycles (PyPI bpy, CPU) and
Mitsuba 3 (llvm_ad_rgb, the grid converted to a dense `.vol`). For each: the
time to a relative MSE of 1e-2 against a long niebla reference, its peak
memory (the process's peak resident set), samples per second; and the
ratios. See bench/README.md, section "Production frame".

    python3 bench/production_frame.py                          # the full frame: 512^3, 1920x1080 (hours on 2 cores)
    python3 bench/production_frame.py --size 256 --width 480   # 480x270, minutes
    python3 bench/production_frame.py --peers cycles           # without Mitsuba
    python3 bench/production_frame.py --memory-only            # 1 spp each at 1920x1080: peak memory, samples/s

Conventions are those of bench/compare.py (box pixel filter, niebla's
max_depth N = Mitsuba's N + 1 = Cycles' N - 1 bounces, no denoising, no
adaptive sampling, no clamping; see bench/niebla2cycles.py and
bench/niebla2mitsuba.py). Every renderer sweeps 1, 2, 4, ... spp until its
error (against niebla's reference, the reference's own noise subtracted) is
below the target; the time to the target is interpolated on log-log axes.

Times, two ways:
- wall: the render call alone (niebla's reported render time; Cycles'
  render call net of its per-call fixed cost, a 1x1-pixel render, mostly
  its volume octree; Mitsuba's mi.render after a JIT warm-up);
- CPU: CPU seconds (user + system, all threads) of the render call, net of
  the same fixed cost measured in CPU seconds (niebla: an 8x8-pixel render
  of the same scene, i.e. start-up, VDB load and majorant grid; Cycles: the
  1x1-pixel render; Mitsuba: none subtracted). On a machine shared with
  other work, CPU seconds are the figures to read. None of them includes
  writing the image: niebla renders with --no-checkpoints (no EXR
  checkpoints between passes) and its CPU seconds are the process CPU time
  it reports before writing its final EXR, as Cycles' render call does not
  save the image. --niebla-with-writes times niebla's whole process
  instead (wait4; checkpoints and final ZIP-compressed EXR included, the
  convention before 2026-12-03 15:00 UTC and the only one for binaries
  without --no-checkpoints).
Memory: niebla's peak RSS is that of each render process (wait4's
ru_maxrss, the largest over the sweep), Cycles' the worker process's VmHWM
after its last render (Blender itself included), Mitsuba's the VmHWM of this
process, reset (/proc/self/clear_refs) just before Mitsuba loads the scene,
with the resident set at that moment given beside it.

The agreement check compares image means: niebla's reference against each
peer's mean of two independent renders at its last sweep spp, with standard
errors from the halves' difference.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import peers  # noqa: E402

peers.ensure_venv(__file__)

import numpy as np  # noqa: E402

import compare  # noqa: E402
from compare import Mitsuba, rel_mse, time_to_reach  # noqa: E402
from peers import read_exr  # noqa: E402
from volumes import vdb_to_vol  # noqa: E402


def vm_status(pid="self") -> dict:
    """VmRSS and VmHWM of a process, in MiB."""
    out = {}
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            k, _, v = line.partition(":")
            if k in ("VmRSS", "VmHWM"):
                out[k] = int(v.split()[0]) / 1024.0
    return out


def make_scene(vdb: str, box_min, box_max, width: int, height: int, max_depth: int) -> dict:
    """The production frame around a cloud in (about) the unit box: sun +
    sky, a gray diffuse floor just below the grid's box, a 16:9 camera."""
    c = [0.5 * (a + b) for a, b in zip(box_min, box_max)]
    return {
        "version": 1,
        "camera": {"type": "perspective", "position": [c[0] + 1.25, c[1] + 0.45, c[2] + 1.9],
                   "target": [c[0], c[1] - 0.05, c[2]], "up": [0, 1, 0], "fov_y": 36,
                   "width": width, "height": height},
        "render": {"integrator": {"type": "volpath", "max_depth": max_depth}, "spp": 16, "seed": 0},
        "media": {
            "cloud": {"type": "grid", "density": {"type": "vdb", "file": vdb},
                      "sigma_t": 20, "albedo": 0.95, "phase": {"type": "hg", "g": 0.5}},
        },
        "shapes": [
            {"type": "box", "min": list(box_min), "max": list(box_max), "interior": "cloud", "bsdf": {"type": "null"}},
            {"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90, "translate": [c[0], box_min[1] - 0.02, c[2]]},
             "bsdf": {"type": "diffuse", "reflectance": [0.4, 0.38, 0.35]}},
        ],
        "lights": [
            {"type": "directional", "direction": [-0.45, -0.75, -0.5], "irradiance": [3.2, 3.0, 2.7]},
            {"type": "constant", "radiance": [0.15, 0.2, 0.3]},
        ],
    }


class MeasuredNiebla(peers.Niebla):
    """peers.Niebla (`niebla render` in a child process; the render time it
    reports, the child's CPU seconds and peak RSS from wait4) with the fixed
    CPU cost taken from an 8x8-pixel copy of the scene. With
    `without_writes`, renders run with --no-checkpoints and the CPU seconds
    are those niebla reports before writing its final EXR."""

    without_writes = True

    def run(self, scene_path, spp, seed, tag, extra=()):
        if not self.without_writes:
            return super().run(scene_path, spp, seed, tag, extra)
        out, t, _, peak, wall = super().run(scene_path, spp, seed, tag, (*extra, "--no-checkpoints"))
        text = self.last_output
        m = re.search(r"process CPU ([0-9.]+) s before the final write", text)
        if not m:
            raise RuntimeError(f"no CPU time in niebla's output {text!r} (use --niebla-with-writes)")
        return out, t, float(m.group(1)), peak, wall

    def fixed(self, tiny_scene):
        """CPU seconds of an 8x8-pixel, 1-spp render (start-up, VDB load,
        majorant grid): the per-call cost that does not grow with pixels or
        samples. The smaller of two."""
        cpu = [self.run(tiny_scene, 1, 90000 + k, f"fixed_{k}")[2] for k in range(2)]
        self.fixed_cpu = min(cpu)
        return self.fixed_cpu

    def render(self, spp, seed, tag):
        """(image, wall render seconds, CPU seconds net of the fixed cost)."""
        out, t, cpu, peak, _ = self.run(self.scene_path, spp, seed, tag)
        self.peak_mib = max(self.peak_mib, peak)
        return read_exr(out), t, max(cpu - self.fixed_cpu, 1e-3)


class MeasuredCycles(peers.Cycles):
    """peers.Cycles giving wall seconds net of the fixed cost and CPU seconds
    (the worker's process time during the render call) net of the 1x1-pixel
    call's."""

    def render(self, spp, seed, tag):
        """(image, wall seconds net of the fixed cost, CPU seconds net of the fixed CPU cost)."""
        img, _, net = super().render(spp, seed, tag)
        return img, net, max(self.cpu_log[-1] - self.fixed_cpu, 1e-3)

    def peak(self):
        return self.peak_mib()


class MeasuredMitsuba(Mitsuba):
    """compare.Mitsuba with the process's CPU seconds during mi.render."""

    def render(self, spp, seed, tag):
        """(image, wall seconds, CPU seconds of the render call)."""
        img, t, _ = super().render(spp, seed, tag)
        return img, t, self.last_cpu


def sweep(r, ref, noise, target, max_spp, cap_s, seed, log):
    """1, 2, 4, ... spp until the error is below `target`, `max_spp` is passed
    or the next render (predicted 2.2x the last, in wall seconds) would pass
    `cap_s` in total. Rows: (spp, wall s, CPU s, rel MSE, image)."""
    rows, spp, spent = [], 1, 0.0
    while spp <= max_spp:
        if rows and spent + 2.2 * rows[-1][1] > cap_s:
            log(f"  {r.name}: stopping (the next render would pass the {cap_s:.0f} s cap)")
            break
        img, wall, cpu = r.render(spp, seed + spp, f"sweep_{spp}")
        spent += wall
        e = max(rel_mse(img, ref) - noise, 1e-12)
        rows.append((spp, wall, cpu, e, img))
        log(f"  {r.name:7s} {spp:5d} spp  {wall:8.2f} s wall  {cpu:8.2f} s CPU  rel MSE {e:.3e}  "
            f"load {os.getloadavg()[0]:.1f}")
        if e < target:
            break
        spp *= 2
    return rows


def summarize(name, rows, target, pixels):
    t_wall, how = time_to_reach([(w, e) for _, w, _, e, _ in rows], target)
    t_cpu, how_c = time_to_reach([(c, e) for _, _, c, e, _ in rows], target)
    spp_at = time_to_reach([(s, e) for s, _, _, e, _ in rows], target)[0]
    spp, wall, cpu = rows[-1][0], rows[-1][1], rows[-1][2]
    return {"renderer": name, "time_wall": t_wall, "how": how, "time_cpu": t_cpu, "how_cpu": how_c,
            "spp_to_target": spp_at, "msamples_per_s": pixels * spp / wall / 1e6,
            "msamples_per_cpu_s": pixels * spp / cpu / 1e6,
            "sweep": [{"spp": s, "wall_s": w, "cpu_s": c, "rel_mse": e} for s, w, c, e, _ in rows]}


def make_peer(peer, desc, scene, args, log):
    """(renderer, sweep seed, this process's RSS before Mitsuba loads in MiB
    or None); (None, ...) when Cycles cannot render the scene."""
    if peer == "cycles":
        r = MeasuredCycles(scene, args.out, args.out, args.threads)
        if r.unsupported:
            log(f"cycles: not compared ({r.unsupported})")
            return None, 0, None
        log(f"cycles: fixed cost per call (1x1 pixel) {r.fixed_s:.2f} s wall, {r.fixed_cpu:.2f} s CPU")
        return r, 30, None
    from llvm import use_newest_llvm

    use_newest_llvm()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    mi.set_log_level(mi.LogLevel.Warn)
    dr.set_thread_count(args.threads)
    import niebla2mitsuba

    base = vm_status()["VmRSS"]
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")  # resets VmHWM to the current RSS
    r = MeasuredMitsuba(niebla2mitsuba.convert(desc, args.out, spp=1))
    log(f"mitsuba: scene load {r.load_s:.1f} s, warm-up (JIT) {r.warmup_s:.1f} s; this process's RSS "
        f"before loading {base:.0f} MiB")
    return r, 50, base


def memory_only(nb, desc, scene, args, pixels, log):
    """One render of `--probe-spp` spp per renderer at the full size: peak
    memory and throughput, no reference and no error."""
    rows = []
    _, wall, cpu = nb.render(args.probe_spp, 1, "probe")
    rows.append(("niebla", wall, cpu, nb.peak_mib, None))
    for peer in args.peers:
        r, _, base = make_peer(peer, desc, scene, args, log)
        if r is None:
            continue
        _, wall, cpu = r.render(args.probe_spp, 1, "probe")
        if peer == "cycles":
            rows.append((peer, wall, cpu, r.peak(), None))
            r.close()
        else:
            rows.append((peer, wall, cpu, vm_status()["VmHWM"], base))
            del r
    log(f"\none render of {args.probe_spp} spp each ({desc['camera']['width']}x{desc['camera']['height']}, "
        f"{args.threads} threads; seconds net of the fixed per-call cost as in the timed run):")
    log("| renderer | wall s | CPU s | Msamples/s (wall) | Msamples/CPU s | peak RSS MiB |")
    log("|---|---|---|---|---|---|")
    for name, wall, cpu, peak, base in rows:
        extra = f" (RSS before loading {base:.0f})" if base is not None else ""
        log(f"| {name} | {wall:.1f} | {cpu:.1f} | {pixels * args.probe_spp / wall / 1e6:.3f} | "
            f"{pixels * args.probe_spp / cpu / 1e6:.3f} | {peak:.0f}{extra} |")
    with open(os.path.join(args.out, "memory.json"), "w") as f:
        json.dump({"width": desc["camera"]["width"], "height": desc["camera"]["height"], "spp": args.probe_spp,
                   "size": args.size, "rows": rows, "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                   "load_average_end": os.getloadavg()[0]}, f, indent=1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=512, help="VDB index box edge in voxels (default 512)")
    ap.add_argument("--balls", type=int, default=8, help="noisy balls in the cloud (make_big_vdb.py)")
    ap.add_argument("--width", type=int, default=1920, help="image width; the height is width * 9 / 16")
    ap.add_argument("--max-depth", type=int, default=64, help="niebla's max_depth (scattering events)")
    ap.add_argument("--ref-spp", type=int, default=1024, help="niebla reference spp (two halves)")
    ap.add_argument("--target", type=float, default=1e-2)
    ap.add_argument("--peers", nargs="*", default=["cycles", "mitsuba"], choices=["cycles", "mitsuba"])
    ap.add_argument("--max-spp", type=int, default=4096, help="largest sweep render")
    ap.add_argument("--cap-seconds", type=float, default=1800, help="wall-time cap of each sweep")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--memory-only", action="store_true",
                    help="one render of --probe-spp spp per renderer: peak memory and throughput, no error")
    ap.add_argument("--probe-spp", type=int, default=1, help="samples per pixel of the --memory-only renders")
    ap.add_argument("--niebla", default=os.path.join(ROOT, "target", "release", "niebla"))
    ap.add_argument("--niebla-with-writes", action="store_true",
                    help="niebla's CPU seconds of the whole process (EXR checkpoints and final write included)")
    ap.add_argument("--out", default=os.path.join(HERE, "out", "production_frame"))
    args = ap.parse_args()
    compare.THREADS = args.threads
    args.out = os.path.abspath(args.out)  # the scene files name the VDB by this path
    width, height = args.width, max(8, round(args.width * 9 / 16))
    pixels = width * height
    os.makedirs(args.out, exist_ok=True)
    t_start = time.perf_counter()

    def log(s):
        print(s, flush=True)

    if not os.path.exists(args.niebla):
        log("building niebla (cargo build --release -p niebla-cli)")
        subprocess.run(["cargo", "build", "--release", "-p", "niebla-cli"], cwd=ROOT, check=True)

    # The grid: reproducible (seeded), written by OpenVDB's own library.
    vdb = os.path.join(args.out, f"cloud_{args.size}_{args.balls}.vdb")
    if not os.path.exists(vdb):
        t0 = time.perf_counter()
        subprocess.run(["/usr/bin/python3", os.path.join(HERE, "make_big_vdb.py"), vdb, "--size", str(args.size),
                        "--balls", str(args.balls), "--seed", "1"], check=True)
        log(f"wrote {vdb} in {time.perf_counter() - t0:.1f} s")
    import niebla2cycles

    lo, hi = niebla2cycles.vdb_grids(vdb)["density"][1:]
    vs = 1.0 / args.size  # make_big_vdb.py's voxel size
    # The container: the active voxels' box plus one voxel (the .vol's box).
    box_min, box_max = [x - vs for x in lo], [x + vs for x in hi]
    vol_info = None
    if "mitsuba" in args.peers:
        nx, ny, nz = (round((b - a) / vs) for a, b in zip(box_min, box_max))
        dense_mib = nx * ny * nz * 4 / 2**20
        avail = next(int(l.split()[1]) for l in open("/proc/meminfo") if l.startswith("MemAvailable")) / 1024
        if 3 * dense_mib > avail:
            log(f"mitsuba: not run: its dense grid ({nx}x{ny}x{nz}, {dense_mib:.0f} MiB as float32, held about "
                f"3 times while converting and loading) does not fit in the {avail:.0f} MiB available")
            args.peers.remove("mitsuba")
        else:
            t0 = time.perf_counter()
            vol_info = vdb_to_vol(vdb, os.path.splitext(vdb)[0] + ".vol")
            box_min, box_max = vol_info["min"], vol_info["max"]
            log(f"the .vol: {vol_info['shape'][::-1]} voxels, {dense_mib:.0f} MiB "
                f"({time.perf_counter() - t0:.1f} s; written only when older than the VDB)")
    desc = make_scene(vdb, box_min, box_max, width, height, args.max_depth)
    scene = os.path.join(args.out, "frame.json")
    with open(scene, "w") as f:
        json.dump(desc, f, indent=1)
    tiny = dict(desc, camera=dict(desc["camera"], width=8, height=8))
    tiny_path = os.path.join(args.out, "frame_8x8.json")
    with open(tiny_path, "w") as f:
        json.dump(tiny, f, indent=1)

    vdb_mib = os.path.getsize(vdb) / 2**20
    log(f"production frame: {width}x{height}, grid {args.size}^3 ({vdb_mib:.1f} MiB VDB), max_depth "
        f"{args.max_depth}, {args.threads} threads, target rel MSE {args.target:g}, load average "
        f"{os.getloadavg()[0]:.2f}, {os.cpu_count()} cores")

    nb = MeasuredNiebla(os.path.abspath(args.niebla), scene, args.out, args.threads)
    nb.without_writes = not args.niebla_with_writes
    log(f"niebla fixed CPU cost per call (8x8 render): {nb.fixed(tiny_path):.2f} s")
    if args.memory_only:
        memory_only(nb, desc, scene, args, pixels, log)
        return
    half = args.ref_spp // 2
    ra, ta, ca = nb.render(half, 1000, "ref_a")
    rb, tb, cb = nb.render(half, 2000, "ref_b")
    ref = 0.5 * (ra + rb)
    noise = compare.ref_noise(ra, rb)
    log(f"niebla reference: {2 * half} spp in {ta + tb:.1f} s wall ({ca + cb:.1f} s CPU); its own rel MSE "
        f"{noise:.2e} ({noise / args.target:.0%} of the target, subtracted)")
    compare.write_png(os.path.join(args.out, "reference_niebla.png"), ref)

    results, means = [], {"niebla reference": (ref, ra, rb, 2 * half)}
    rows = sweep(nb, ref, noise, args.target, args.max_spp, args.cap_seconds, 10, log)
    res = summarize("niebla", rows, args.target, pixels)
    res["peak_rss_mib"] = nb.peak_mib
    results.append(res)

    for peer in args.peers:
        r, seed, base = make_peer(peer, desc, scene, args, log)
        if r is None:
            continue
        prow = sweep(r, ref, noise, args.target, args.max_spp, args.cap_seconds, seed, log)
        res = summarize(peer, prow, args.target, pixels)
        # A second render at the last spp, for the image-mean check.
        spp = prow[-1][0]
        extra, _, _ = r.render(spp, seed + 7777, "check")
        means[peer] = (0.5 * (prow[-1][4] + extra), prow[-1][4], extra, 2 * spp)
        if peer == "cycles":
            res["peak_rss_mib"] = r.peak()
            r.close()
        else:
            res["peak_rss_mib"] = vm_status()["VmHWM"]
            res["rss_before_load_mib"] = base
            del r
        results.append(res)

    total = time.perf_counter() - t_start
    log("\nimage means against niebla's reference (R, G, B; peer / niebla - 1 +- one standard error):")
    log("| image | spp | mean R | mean G | mean B | / niebla - 1 (R, G, B) |")
    log("|---|---|---|---|---|---|")
    n_mean = ref.astype(np.float64).mean((0, 1))
    n_se = compare.mean_stderr(ra, rb)
    for k, (img, a, b, spp) in means.items():
        mn = img.astype(np.float64).mean((0, 1))
        se = np.sqrt(compare.mean_stderr(a, b) ** 2 + (0 if k.startswith("niebla") else n_se ** 2))
        d = "-" if k.startswith("niebla") else ", ".join(
            f"{x:+.4f} +- {s:.4f}" for x, s in zip(mn / n_mean - 1, se / n_mean))
        log(f"| {k} | {spp} | {mn[0]:.5f} | {mn[1]:.5f} | {mn[2]:.5f} | {d} |")

    mark = {"interp": "", "first": "<=", "extrap": "~", "none": "?"}
    log(f"\ntime to rel MSE {args.target:g} ({width}x{height}, {args.threads} threads; '~' extrapolated as "
        f"1/time past the last render, '<=' reached at 1 spp):")
    log("| renderer | spp to target | wall s | CPU s | Msamples/s (wall) | Msamples/CPU s | peak RSS MiB |")
    log("|---|---|---|---|---|---|---|")
    for r in results:
        log(f"| {r['renderer']} | {r['spp_to_target']:.0f} | {mark[r['how']]}{r['time_wall']:.1f} | "
            f"{mark[r['how_cpu']]}{r['time_cpu']:.1f} | {r['msamples_per_s']:.3f} | {r['msamples_per_cpu_s']:.3f} | "
            f"{r['peak_rss_mib']:.0f} |")
    n = results[0]
    for r in results[1:]:
        log(f"{r['renderer']} / niebla: time {r['time_wall'] / n['time_wall']:.2f}x wall, "
            f"{r['time_cpu'] / n['time_cpu']:.2f}x CPU; peak memory {r['peak_rss_mib'] / n['peak_rss_mib']:.2f}x")
    summary = {"width": width, "height": height, "size": args.size, "balls": args.balls, "vdb_mib": vdb_mib,
               "max_depth": args.max_depth, "threads": args.threads, "target": args.target,
               "ref_spp": 2 * half, "ref_noise": noise, "total_s": total, "results": results,
               "means": {k: v[0].astype(np.float64).mean((0, 1)).tolist() for k, v in means.items()},
               "load_average_end": os.getloadavg()[0], "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump(summary, f, indent=1)
    log(f"total {total / 60:.1f} min; details in {os.path.join(args.out, 'results.json')}")


if __name__ == "__main__":
    main()
