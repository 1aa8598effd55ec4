#!/usr/bin/env python3
"""Speed comparison of niebla against Mitsuba 3 (llvm_ad_rgb, volpath /
volpathmis) on the scenes of bench/scenes: for each scene, the time each
renderer needs to reach a relative MSE of 1e-2 against a high-spp
reference, and their ratio. See bench/README.md.

    python3 bench/compare.py            # full run: 128x128, ~8-10 min on 2 cores
    python3 bench/compare.py --quick    # ~3 min: 96x96, smaller budgets
    python3 bench/compare.py --scenes --xml-scenes grid_smoke area_fog
    nice -n 10 python3 bench/compare.py --quick --peers mitsuba cycles --threads 1 --clock cpu   # shared machine

`--xml-scenes` adds Mitsuba 3 XML scenes from scenes/mitsuba/ read directly
by both renderers (no converter on niebla's side: `niebla render NAME.xml`,
and `mi.load_file` for Mitsuba), at the resolution the file gives (--scale
does not apply) and with the sampler it names (niebla follows the XML's
`independent`); they appear as xml:NAME in the table.

It re-runs itself with bench/.venv/bin/python (creating the venv with
bench/setup.sh when it is missing; bench/peers.py).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import peers  # noqa: E402

peers.ensure_venv(__file__)

import numpy as np  # noqa: E402

import niebla2mitsuba  # noqa: E402
from peers import Cycles  # noqa: E402
from volumes import ensure_volumes  # noqa: E402

SCENES = ["fog_spot", "fog_point", "smoke_plume", "dense_cloud", "milk_cube"]
# Mitsuba 3 XML scenes (scenes/mitsuba/NAME.xml) both renderers read as they are.
XML_DIR = os.path.join(ROOT, "scenes", "mitsuba")
XML_SCENES = sorted(f[:-4] for f in os.listdir(XML_DIR) if f.endswith(".xml")) if os.path.isdir(XML_DIR) else []
# Not in the default set: a homogeneous slab (optical thickness 2, albedo 0.9,
# HG 0.5) under a sun at normal incidence, seen from 45 degrees above.
EXTRA_SCENES = ["slab"]
# Reference budget per scene, as a multiple of --ref-seconds: roughly in
# proportion to how long the renderers take to reach the target there, so that
# every reference's own error stays a small fraction of the target.
REF_WEIGHT = {"fog_spot": 3.0, "fog_point": 1.0, "smoke_plume": 0.5, "dense_cloud": 1.5, "milk_cube": 0.5, "slab": 1.0}
THREADS = 2
# "wall": each renderer's render time as below; "cpu": the CPU seconds (user +
# system, all threads) of the render calls, net of fixed per-call costs
# (--clock).
CLOCK = "wall"
# Whether niebla's times exclude its output writes (peers.Niebla's
# `no_writes`: --no-checkpoints, CPU seconds before the final EXR);
# --niebla-with-writes turns it off (the convention before 2026-12-03).
NO_WRITES = True


# ---------------------------------------------------------------------------
# Error measure (niebla's Image::relative_mse, crates/niebla/src/film/mod.rs)
# ---------------------------------------------------------------------------


def rel_mse(x: np.ndarray, r: np.ndarray) -> float:
    """Mean over pixels and channels of (x - r)^2 / (r^2 + eps), eps = (0.01 mean(r))^2."""
    x = x.astype(np.float64)
    r = r.astype(np.float64)
    eps = max((0.01 * r.mean()) ** 2, np.finfo(float).tiny)
    return float(np.mean((x - r) ** 2 / (r * r + eps)))


def time_to_reach(points, target):
    """Log-log interpolation of (time, error) points (increasing time) at
    `target`, as niebla's bench does. Returns (time, how): how is 'interp',
    'first' (already below at the first point: its time, an upper bound) or
    'extrap' (never reached: extrapolated from the last point assuming
    error ~ 1/time, the Monte Carlo rate)."""
    pts = [(t, e) for t, e in points if t > 0 and e > 0]
    if not pts:
        return None, "none"
    for i, (t, e) in enumerate(pts):
        if e < target:
            if i == 0:
                return t, "first"
            (t0, e0), (t1, e1) = pts[i - 1], pts[i]
            f = (np.log(target) - np.log(e0)) / (np.log(e1) - np.log(e0))
            return float(np.exp(np.log(t0) + f * (np.log(t1) - np.log(t0)))), "interp"
    t, e = pts[-1]
    return t * e / target, "extrap"


# ---------------------------------------------------------------------------
# Renderers
# ---------------------------------------------------------------------------


class Niebla(peers.Niebla):
    """peers.Niebla with this script's thread count, clock and write convention."""

    def __init__(self, binary: str, scene_path: str, workdir: str):
        super().__init__(binary, scene_path, workdir, THREADS, CLOCK, no_writes=NO_WRITES)


class Mitsuba:
    name = "mitsuba"
    MAX_LANES = 1 << 22  # larger renders are split into passes of at most this many samples

    def __init__(self, scene):
        """`scene`: a scene dict (niebla2mitsuba.convert) or the path of a
        Mitsuba XML file."""
        import drjit as dr
        import mitsuba as mi

        self.dr, self.mi = dr, mi
        t0 = time.perf_counter()
        self.scene = mi.load_file(scene) if isinstance(scene, str) else mi.load_dict(scene)
        self.load_s = time.perf_counter() - t0
        film = self.scene.sensors()[0].film().size()
        self.chunk_spp = max(1, self.MAX_LANES // (int(film[0]) * int(film[1])))
        # Warm-up: JIT-compiles (or loads from Dr.Jit's kernel cache) the
        # rendering kernel, so the timed renders below exclude compilation.
        # The kernel does not depend on spp or seed (checked: no recompiles).
        t0 = time.perf_counter()
        self._render(1, 999999)
        self.warmup_s = time.perf_counter() - t0

    def _render(self, spp: int, seed: int):
        dr, mi = self.dr, self.mi
        acc, done, k = None, 0, 0
        while done < spp:
            n = min(self.chunk_spp, spp - done)
            img = mi.render(self.scene, spp=n, seed=(seed * 1024 + k) % (1 << 31))
            dr.eval(img)
            dr.sync_thread()
            acc = img * n if acc is None else acc + img * n
            dr.eval(acc)
            done += n
            k += 1
        dr.sync_thread()
        return acc / spp

    def render(self, spp: int, seed: int, tag: str):
        """Returns (image, seconds, wall seconds): the time of mi.render (plus
        dr.eval and a sync) after the warm-up render; with CLOCK "cpu" the
        first is this process's CPU seconds (user + system, Dr.Jit's threads
        included) over the same span, stored in `last_cpu` either way."""
        t0, c0 = time.perf_counter(), time.process_time()
        img = self._render(spp, seed)
        t, self.last_cpu = time.perf_counter() - t0, time.process_time() - c0
        arr = np.array(img, dtype=np.float32)[..., :3]
        return arr, (self.last_cpu if CLOCK == "cpu" else t), t


# ---------------------------------------------------------------------------
# The comparison
# ---------------------------------------------------------------------------


def prepare_scene(name: str, outdir: str, scale: float) -> tuple[str, dict]:
    """Writes the scene with absolute data paths (and the resolution scaled by
    `scale`) to outdir; returns its path and parsed description."""
    src = os.path.join(HERE, "scenes", name + ".json")
    with open(src) as f:
        desc = json.load(f)
    cam = desc["camera"]
    cam["width"] = max(8, int(round(cam["width"] * scale)))
    cam["height"] = max(8, int(round(cam["height"] * scale)))
    for m in desc.get("media", {}).values():
        d = m.get("density")
        if d and "file" in d:
            d["file"] = os.path.join(HERE, "scenes", d["file"])
    path = os.path.join(outdir, name + ".json")
    with open(path, "w") as f:
        json.dump(desc, f, indent=1)
    return path, desc


def prepare_xml_scene(binary: str, name: str, outdir: str) -> tuple[str, dict, dict]:
    """scenes/mitsuba/NAME.xml as it is: its path, the niebla scene niebla
    reads from it (`niebla convert`, for the resolution and depth in the
    table) and the XML's integrator (type and max_depth) as Mitsuba reads it."""
    import xml.etree.ElementTree as ET

    path = os.path.join(XML_DIR, name + ".xml")
    conv = os.path.join(outdir, name + "_as_niebla.json")
    p = subprocess.run([binary, "convert", path, "-o", conv], capture_output=True, text=True)
    if p.returncode:
        raise RuntimeError(f"niebla convert {path} failed:\n{p.stderr}")
    with open(conv) as f:
        desc = json.load(f)
    integ = ET.parse(path).getroot().find("integrator")
    info = {"integrator": integ.get("type") if integ is not None else "path", "max_depth": -1}
    for c in integ if integ is not None else []:
        if c.get("name") == "max_depth":
            info["max_depth"] = int(c.get("value"))
    return path, desc, info


def reference(renderer, spp: int, seed0: int, log):
    """Two independent halves (spp/2 each); returns (mean, half a, half b, seconds)."""
    half = max(1, spp // 2)
    a, ta, _ = renderer.render(half, seed0, "ref_a")
    b, tb, _ = renderer.render(half, seed0 + 1, "ref_b")
    log(f"    {renderer.name} reference: {2 * half} spp in {ta + tb:.1f} s")
    return 0.5 * (a + b), a, b, ta + tb


def ref_noise(a: np.ndarray, b: np.ndarray) -> float:
    """Relative MSE of the mean of two independent halves against the truth,
    estimated from their difference: E|a-b|^2 = 2 var(half) = 4 var(mean)."""
    return _rel_mse_den(a - b, 0.5 * (a + b)) / 4.0


def _rel_mse_den(diff: np.ndarray, r: np.ndarray) -> float:
    diff = diff.astype(np.float64)
    r = r.astype(np.float64)
    eps = max((0.01 * r.mean()) ** 2, np.finfo(float).tiny)
    return float(np.mean(diff**2 / (r * r + eps)))


def block_mean(img: np.ndarray, k: int) -> np.ndarray:
    h, w = img.shape[0] // k * k, img.shape[1] // k * k
    x = img[:h, :w].astype(np.float64)
    return x.reshape(h // k, k, w // k, k, -1).mean(axis=(1, 3))


def mean_stderr(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Standard error (per channel) of the image mean of (a + b) / 2, from two
    independent halves: each pixel's variance of the mean is ~ (a - b)^2 / 4."""
    d = (a.astype(np.float64) - b.astype(np.float64)) ** 2 / 4.0
    return np.sqrt(d.sum(axis=(0, 1))) / (a.shape[0] * a.shape[1])


def agreement(n_ref, m_ref, n_noise, m_noise, block: int, n_halves, m_halves):
    """How far the two references are apart, beyond their noise."""
    n64, m64 = n_ref.astype(np.float64), m_ref.astype(np.float64)
    mean_n, mean_m = n64.mean(axis=(0, 1)), m64.mean(axis=(0, 1))
    se = np.sqrt(mean_stderr(*n_halves) ** 2 + mean_stderr(*m_halves) ** 2)
    e = rel_mse(m_ref, n_ref)
    bn, bm = block_mean(n64, block), block_mean(m64, block)
    floor = 0.01 * bn.mean()
    rel = (bm - bn) / (np.abs(bn) + floor)  # signed, per block and channel
    lum_rel = rel.mean(axis=2)
    absrel = np.abs(rel)
    return {
        "mean_rgb_niebla": mean_n.tolist(),
        "mean_rgb_peer": mean_m.tolist(),
        "mean_rel_diff_rgb": ((mean_m - mean_n) / mean_n).tolist(),
        "mean_rel_diff_stderr_rgb": (se / mean_n).tolist(),
        "mean_diff_z_rgb": ((mean_m - mean_n) / se).tolist(),
        "rel_mse": e,
        "rel_mse_expected_from_noise": n_noise + m_noise,
        "rel_mse_excess": e - (n_noise + m_noise),
        "block": block,
        "block_rel_diff_mean": float(rel.mean()),
        "block_abs_rel_diff_median": float(np.median(absrel)),
        "block_abs_rel_diff_p90": float(np.percentile(absrel, 90)),
        "block_abs_rel_diff_p99": float(np.percentile(absrel, 99)),
        "block_abs_rel_diff_max": float(absrel.max()),
        "_lum_rel_map": lum_rel,
    }


def write_png(path: str, img: np.ndarray, exposure: float = 0.0):
    import mitsuba as mi

    with peers.bitmap_io():
        mi.util.write_bitmap(path, (img * 2.0**exposure).astype(np.float32), write_async=False)


def diff_png(path: str, lum_rel: np.ndarray, scale: float = 0.1):
    """Signed relative difference map: red where the peer is brighter, blue
    where niebla is; full saturation at +-scale."""
    t = np.clip(lum_rel / scale, -1, 1)
    rgb = np.stack([np.clip(t, 0, 1), np.zeros_like(t), np.clip(-t, 0, 1)], axis=-1)
    rgb = np.kron(rgb, np.ones((4, 4, 1)))
    import mitsuba as mi

    with peers.bitmap_io():
        mi.Bitmap(rgb.astype(np.float32)).convert(srgb_gamma=True, component_format=mi.Struct.Type.UInt8).write(path)


def sweep(renderer, reference_img, noise, target, cap_s, max_spp, seed, log, other_ref=None, other_noise=0.0):
    """Renders at 1, 2, 4, ... spp until the (noise-corrected) error is below
    the target or the next render (predicted 2.2x the last) would not fit in
    the time cap."""
    rows = []
    spp, spent, last_t = 1, 0.0, 0.0
    while spp <= max_spp:
        # Predict the next render time from the last one (doubling spp).
        if rows and spent + 2.2 * last_t > cap_s:
            break
        img, t, wall = renderer.render(spp, seed, f"sweep_{spp}")
        spent += t
        last_t = t
        raw = rel_mse(img, reference_img)
        row = {"spp": spp, "seconds": t, getattr(renderer, "third", "wall_seconds"): wall, "rel_mse_raw": raw, "rel_mse": max(raw - noise, 1e-12)}
        if other_ref is not None:
            raw2 = rel_mse(img, other_ref)
            row.update(rel_mse_own_raw=raw2, rel_mse_own=max(raw2 - other_noise, 1e-12))
        rows.append(row)
        log(f"    {renderer.name:8s} {spp:5d} spp {t:8.3f} s  rel MSE {row['rel_mse']:.3e}"
            + (f" (vs own ref {row['rel_mse_own']:.3e})" if other_ref is not None else ""))
        done = row["rel_mse"] < target
        if other_ref is not None:
            done = done and row["rel_mse_own"] < target
        if done:
            break
        spp *= 2
    return rows


def versions(binary: str, label: str | None) -> dict:
    import drjit as dr
    import mitsuba as mi

    v = {}
    v["niebla"] = subprocess.run([binary, "--version"], capture_output=True, text=True).stdout.strip()
    if label:
        v["niebla_build"] = label
    elif os.path.realpath(binary) == os.path.realpath(os.path.join(ROOT, "target", "release", "niebla")):
        g = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True, text=True)
        v["niebla_build"] = f"working tree {g.stdout.strip()} (target/release; may be older than the tree)"
    else:
        v["niebla_build"] = "external binary (pass --niebla-label to record its revision)"
    v["niebla_binary"] = binary
    v["mitsuba"] = mi.__version__
    v["drjit"] = dr.__version__
    v["variant"] = mi.variant()
    v["llvm"] = next((l.split()[-1] for l in open("/proc/self/maps") if "libLLVM" in l), "?")
    v["python"] = platform.python_version()
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        cpu = platform.processor()
    v["cpu"] = f"{cpu}, {os.cpu_count()} logical cores"
    return v


def main():
    global THREADS, CLOCK, NO_WRITES
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="96x96 and smaller budgets (~3 min)")
    ap.add_argument("--scale", type=float, default=None,
                    help="resolution relative to the scene files' 256x256 (default 0.5 = 128x128, quick 0.375 = 96x96)")
    ap.add_argument("--scenes", nargs="*", default=SCENES, choices=SCENES + EXTRA_SCENES)
    ap.add_argument("--xml-scenes", nargs="*", default=[], choices=XML_SCENES,
                    help="Mitsuba 3 XML scenes from scenes/mitsuba/, read directly by both renderers")
    ap.add_argument("--peers", nargs="+", default=["mitsuba"], choices=["mitsuba", "cycles"],
                    help="renderers to compare niebla with (cycles: Blender Cycles 5.0 from PyPI bpy, in bench/.venv-cycles)")
    ap.add_argument("--niebla", default=os.path.join(ROOT, "target", "release", "niebla"),
                    help="niebla binary (default target/release/niebla; built if missing)")
    ap.add_argument("--niebla-label", default=None, help="free text recorded as the niebla build (e.g. its git revision)")
    ap.add_argument("--mitsuba-integrator", default="auto", choices=["auto", "volpath", "volpathmis"],
                    help="auto: volpathmis for chromatic media, else volpath")
    ap.add_argument("--target", type=float, default=1e-2, help="relative MSE to reach")
    ap.add_argument("--ref-seconds", type=float, default=None,
                    help="reference budget per renderer, times the scene's REF_WEIGHT (default 40, quick 12)")
    ap.add_argument("--sweep-seconds", type=float, default=None,
                    help="time cap of each renderer's spp sweep per scene (default 40, quick 10)")
    ap.add_argument("--out", default=os.path.join(HERE, "out"))
    ap.add_argument("--threads", type=int, default=THREADS, help=f"threads of every renderer (default {THREADS})")
    ap.add_argument("--clock", default="wall", choices=["wall", "cpu"],
                    help="wall: render times as reported (default); cpu: CPU seconds (user + system) of the render "
                         "calls, net of fixed per-call costs (niebla: an 8-pixel-wide 1-spp render of the scene; "
                         "Cycles: a 1x1-pixel render; Mitsuba: none), for a shared machine")
    ap.add_argument("--niebla-with-writes", action="store_true",
                    help="time niebla with its EXR checkpoints and final write (default: without, "
                         "--no-checkpoints and the CPU seconds it reports before the final write)")
    args = ap.parse_args()
    THREADS, CLOCK = args.threads, args.clock
    NO_WRITES = not args.niebla_with_writes

    scale = args.scale or (0.375 if args.quick else 0.5)
    ref_s = args.ref_seconds or (12.0 if args.quick else 40.0)
    sweep_s = args.sweep_seconds or (10.0 if args.quick else 40.0)

    from llvm import use_newest_llvm

    use_newest_llvm()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    mi.set_log_level(mi.LogLevel.Warn)
    dr.set_thread_count(THREADS)
    if "cycles" in args.peers:
        peers.ensure_cycles()

    if not os.path.exists(args.niebla):
        print("building niebla (cargo build --release -p niebla-cli)", flush=True)
        subprocess.run(["cargo", "build", "--release", "-p", "niebla-cli"], cwd=ROOT, check=True)
    binary = os.path.abspath(args.niebla)

    os.makedirs(args.out, exist_ok=True)
    ensure_volumes()
    ver = versions(binary, args.niebla_label)
    if "cycles" in args.peers:
        ver["cycles"] = peers.cycles_version()
    print("versions:", json.dumps(ver, indent=1), flush=True)
    print(f"threads: niebla --threads {THREADS}, Dr.Jit thread count {dr.thread_count()}, Cycles {THREADS} threads; "
          f"{'quick' if args.quick else 'full'} mode: resolution x{scale}, reference ~{ref_s:.0f} s "
          f"per renderer, sweep cap {sweep_s:.0f} s"
          + ("; times in CPU seconds net of fixed per-call costs (budgets and caps too)" if CLOCK == "cpu" else ""),
          flush=True)

    def log(s):
        print(s, flush=True)

    results = []
    t_start = time.perf_counter()
    for label in args.scenes + ["xml:" + x for x in args.xml_scenes]:
        is_xml = label.startswith("xml:")
        name = label[4:] if is_xml else label
        sdir = os.path.join(args.out, "quick" if args.quick else "full", label.replace(":", "_"))
        os.makedirs(sdir, exist_ok=True)
        if is_xml:
            path, desc, xml_integ = prepare_xml_scene(binary, name, sdir)
        else:
            path, desc = prepare_scene(name, sdir, scale)
        w, h = desc["camera"]["width"], desc["camera"]["height"]
        load0 = os.getloadavg()[0]
        log(f"\n== {label} ({w}x{h}), load average {load0:.2f}")

        nb = Niebla(binary, path, sdir)
        if CLOCK == "cpu":
            log(f"    niebla fixed CPU cost per render call (8-pixel-wide render, subtracted): "
                f"{nb.measure_fixed_cpu():.3f} s")
        runners, peer_info = [], {}
        for peer in args.peers:
            if peer == "mitsuba" and is_xml:
                ms = Mitsuba(path)
                peer_info["mitsuba"] = dict(xml_integ, warmup_s=ms.warmup_s)
                log(f"    mitsuba (from the XML) {xml_integ['integrator']} max_depth {xml_integ['max_depth']}: "
                    f"scene load {ms.load_s:.2f} s, warm-up render (JIT) {ms.warmup_s:.2f} s")
                runners.append(ms)
            elif is_xml:
                log(f"    {peer}: not compared (an XML scene; only Mitsuba reads it)")
                peer_info[peer] = {"unsupported": "XML scene"}
            elif peer == "mitsuba":
                mdict = niebla2mitsuba.convert(desc, os.path.join(HERE, "scenes"), spp=1,
                                               integrator=args.mitsuba_integrator)
                ms = Mitsuba(mdict)
                peer_info["mitsuba"] = {"integrator": mdict["integrator"]["type"],
                                        "max_depth": mdict["integrator"]["max_depth"], "warmup_s": ms.warmup_s}
                log(f"    mitsuba {mdict['integrator']['type']} max_depth {mdict['integrator']['max_depth']}: "
                    f"scene load {ms.load_s:.2f} s, warm-up render (JIT) {ms.warmup_s:.2f} s")
                runners.append(ms)
            else:
                cy = Cycles(path, os.path.join(HERE, "scenes"), sdir, THREADS, CLOCK)
                if cy.unsupported:
                    log(f"    cycles: not compared ({cy.unsupported})")
                    peer_info["cycles"] = {"unsupported": cy.unsupported}
                    continue
                peer_info["cycles"] = {"fixed_s": cy.fixed_s, "fixed_cpu_s": cy.fixed_cpu}
                log(f"    cycles: fixed cost per render call (1x1 pixel, 1 spp) {cy.fixed_s:.2f} s wall, "
                    f"{cy.fixed_cpu:.2f} s CPU")
                runners.append(cy)

        # Throughput probes (4 spp) size the references to the time budget.
        budget = ref_s * REF_WEIGHT.get(name, 1.0)
        # Twice, the faster counted: a first render may include one-time costs.
        tn = min(nb.render(4, 7, "probe")[1] for _ in range(2))
        spp_n = int(max(8, min(1 << 16, budget / (tn / 4)))) // 2 * 2
        n_ref, na, nbb, n_ref_t = reference(nb, spp_n, 1001, log)
        n_noise = ref_noise(na, nbb)
        write_png(os.path.join(sdir, "reference_niebla.png"), n_ref)
        log(f"    reference noise (rel MSE): niebla {n_noise:.2e} ({spp_n} spp)")
        if n_noise > 0.25 * args.target:
            log(f"    warning: the niebla reference's own error is {n_noise / args.target:.0%} of the target; "
                "the correction below is large (raise --ref-seconds)")
        n_rows = sweep(nb, n_ref, n_noise, args.target, sweep_s, 1 << 14, 1, log)
        tn_, how_n = time_to_reach([(r["seconds"], r["rel_mse"]) for r in n_rows], args.target)
        last_n = n_rows[-1]
        res = {
            "scene": label, "width": w, "height": h,
            "max_depth_niebla": desc["render"]["integrator"].get("max_depth"),
            "niebla_time": tn_, "niebla_how": how_n,
            "niebla_msamples_s": w * h * last_n["spp"] / last_n["seconds"] / 1e6,
            "reference": {"niebla_spp": spp_n, "niebla_seconds": n_ref_t, "niebla_noise": n_noise},
            "niebla_sweep": n_rows,
            "peers": peer_info,
        }
        for pr in runners:
            tp = min(pr.render(4, 7, "probe")[1] for _ in range(2))
            spp_p = int(max(8, min(1 << 16, budget / (tp / 4)))) // 2 * 2
            p_ref, pa, pb, p_ref_t = reference(pr, spp_p, 2001, log)
            p_noise = ref_noise(pa, pb)
            agree = agreement(n_ref, p_ref, n_noise, p_noise, max(4, w // 32), (na, nbb), (pa, pb))
            lum_rel = agree.pop("_lum_rel_map")
            write_png(os.path.join(sdir, f"reference_{pr.name}.png"), p_ref)
            diff_png(os.path.join(sdir, f"reference_rel_diff_{pr.name}.png"), lum_rel)
            log(f"    {pr.name} reference noise (rel MSE) {p_noise:.2e} ({spp_p} spp); mean rel diff ({pr.name}-niebla)/niebla R G B = "
                + " ".join(f"{x:+.4f}" for x in agree["mean_rel_diff_rgb"])
                + " (+-" + " ".join(f"{x:.4f}" for x in agree["mean_rel_diff_stderr_rgb"]) + " std. error, z "
                + " ".join(f"{x:+.1f}" for x in agree["mean_diff_z_rgb"]) + ")"
                + f"; rel MSE {agree['rel_mse']:.2e} (noise alone ~{agree['rel_mse_expected_from_noise']:.2e})")
            log(f"    {agree['block']}x{agree['block']}-pixel blocks, |rel diff|: median {agree['block_abs_rel_diff_median']:.4f}, "
                f"p90 {agree['block_abs_rel_diff_p90']:.4f}, p99 {agree['block_abs_rel_diff_p99']:.4f}, "
                f"max {agree['block_abs_rel_diff_max']:.4f}; signed mean {agree['block_rel_diff_mean']:+.4f}")
            rows = sweep(pr, n_ref, n_noise, args.target, sweep_s, 1 << 14, 1, log, other_ref=p_ref, other_noise=p_noise)
            t_, how = time_to_reach([(r["seconds"], r["rel_mse"]) for r in rows], args.target)
            to, how_o = time_to_reach([(r["seconds"], r["rel_mse_own"]) for r in rows], args.target)
            tnet, how_net = time_to_reach([(r.get("net_seconds", r["seconds"]), r["rel_mse"]) for r in rows], args.target)
            last = rows[-1]
            res["peers"][pr.name].update({
                "time": t_, "how": how, "time_own_ref": to, "how_own_ref": how_o,
                "time_net": tnet if pr.name == "cycles" else None, "how_net": how_net,
                "ratio": (t_ / tn_) if tn_ and t_ else None,
                "ratio_own_ref": (to / tn_) if tn_ and to else None,
                "ratio_net": (tnet / tn_) if pr.name == "cycles" and tn_ and tnet else None,
                "msamples_s": w * h * last["spp"] / last["seconds"] / 1e6,
                "reference": {"spp": spp_p, "seconds": p_ref_t, "noise": p_noise},
                "agreement": agree, "sweep": rows,
            })
            if isinstance(pr, Cycles):
                pr.close()
        res["load_average"] = [load0, os.getloadavg()[0]]
        results.append(res)
        del runners

    total = time.perf_counter() - t_start
    mark = {"interp": "", "first": "<=", "extrap": "~", "none": "?"}

    def fmt_t(t, how):
        return "n/a" if t is None else f"{mark[how]}{t:.3g} s"

    def fmt_r(x):
        return "n/a" if x is None else f"{x:.2f}"

    print(f"\nTime to relative MSE {args.target:g} (all against the niebla reference, reference noise "
          f"subtracted); {THREADS} threads each; {'CPU seconds, ' if CLOCK == 'cpu' else ''}"
          f"total {total / 60:.1f} min\n")
    hdr = f"{'scene':20s} {'res':>7s} {'niebla':>10s} {'niebla Ms/s':>11s}"
    for p in args.peers:
        hdr += f" | {p:>8s} {'ratio':>6s} {p + '*':>9s} {'ratio*':>6s}"
        if p == "cycles":
            hdr += f" {'net':>9s} {'ratio':>6s}"
        hdr += f" {'Ms/s':>6s} {'ref diff':>8s}"
    print(hdr)
    print("-" * len(hdr))
    for r in results:
        line = f"{r['scene']:20s} {r['width']}x{r['height']:<3d} {fmt_t(r['niebla_time'], r['niebla_how']):>10s} {r['niebla_msamples_s']:11.3f}"
        for p in args.peers:
            q = r["peers"].get(p, {})
            if "time" not in q:
                line += f" | {'n/a':>8s} {'':6s} {'':9s} {'':6s}" + (f" {'':9s} {'':6s}" if p == "cycles" else "") + f" {'':6s} {'':8s}"
                continue
            line += (f" | {fmt_t(q['time'], q['how']):>8s} {fmt_r(q['ratio']):>6s} {fmt_t(q['time_own_ref'], q['how_own_ref']):>9s}"
                     f" {fmt_r(q['ratio_own_ref']):>6s}")
            if p == "cycles":
                line += f" {fmt_t(q['time_net'], q['how_net']):>9s} {fmt_r(q['ratio_net']):>6s}"
            line += f" {q['msamples_s']:6.3f} {np.mean(q['agreement']['mean_rel_diff_rgb']):+8.4f}"
        print(line)
    print("\nratio: peer time / niebla time. peer*: the peer against its own reference. cycles net: minus its fixed "
          "per-call cost (scene synchronisation, volume octree). '~': not reached within the sweep cap, extrapolated "
          "as error ~ 1/time; '<=': already reached at 1 spp. ref diff: mean relative difference of the references' "
          "image means, (peer - niebla) / niebla, averaged over R, G, B.")
    for r in results:
        for p, q in r["peers"].items():
            if "unsupported" in q:
                print(f"{r['scene']}: {p} not compared: {q['unsupported']}")
    summary = {"versions": ver, "quick": args.quick, "target": args.target, "threads": THREADS, "clock": CLOCK,
               "total_seconds": total, "results": results}
    out_json = os.path.join(args.out, "results_quick.json" if args.quick else "results.json")
    with open(out_json, "w") as f:
        json.dump(summary, f, indent=1)
    print(f"details: {out_json}; images under {args.out}/{'quick' if args.quick else 'full'}/<scene>/")


if __name__ == "__main__":
    main()
