#!/usr/bin/python3
"""niebla alone on a scene: time to a relative MSE of 1e-2 for one or more
niebla binaries, interleaved (for before/after comparisons on a shared
machine), without Mitsuba or Cycles and without bench/.venv: Debian's
/usr/bin/python3 with numpy is enough (EXRs are read by the small reader
below, which handles niebla's scanline float/half outputs, uncompressed or
ZIP).

    /usr/bin/python3 bench/niebla_time_to_target.py SCENE.json REF_A.exr REF_B.exr \
        --bin old=/tmp/niebla_old --bin new=target/release/niebla [--spp 4,8,16] [--threads 2]

REF_A and REF_B are two independent renders of SCENE (different --seed);
their mean is the reference and its own error (rel_mse(a, b) / 4) is
subtracted, as bench/production_frame.py does. Each binary renders SCENE at
each spp (seed 77 + spp) with --no-checkpoints; its CPU seconds are the
process CPU time niebla reports at the end of rendering, before it writes
the (ZIP-compressed) EXR, as Cycles' and Mitsuba's render-call times leave
out saving the image. They are net of the smaller of two 1-spp renders of
the scene at 8x8 pixels (start-up, grid load, majorant grid); the time to
1e-2 is interpolated on log-log axes between the sweep points that bracket
it. --with-writes times the whole process instead (user + system, wait4,
checkpoint writes between passes and the final write included): the
convention before 2026-12-03 15:00 UTC, and the only one for binaries
without --no-checkpoints.
"""
import argparse
import json
import math
import os
import re
import struct
import subprocess
import tempfile
import zlib

import numpy as np


def read_exr(path):
    """RGB of a scanline EXR with float or half channels (NONE, ZIPS, ZIP)."""
    b = open(path, "rb").read()
    assert struct.unpack_from("<I", b, 0)[0] == 20000630, f"{path}: not an EXR"
    pos, attrs = 8, {}
    while b[pos] != 0:
        e = b.index(b"\0", pos)
        name = b[pos:e].decode()
        e2 = b.index(b"\0", e + 1)
        size = struct.unpack_from("<i", b, e2 + 1)[0]
        attrs[name] = b[e2 + 5:e2 + 5 + size]
        pos = e2 + 5 + size
    pos += 1
    channels, cb, p = [], attrs["channels"], 0
    while cb[p] != 0:
        e = cb.index(b"\0", p)
        channels.append((cb[p:e].decode(), struct.unpack_from("<i", cb, e + 1)[0]))
        p = e + 17
    comp = attrs["compression"][0]
    assert comp in (0, 2, 3), f"{path}: compression {comp} not handled"
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = 16 if comp == 3 else 1
    offsets = struct.unpack_from(f"<{(h + lines - 1) // lines}Q", b, pos)
    out = {n: np.zeros((h, w), np.float32) for n, _ in channels}
    for o in offsets:
        y, size = struct.unpack_from("<ii", b, o)
        data = b[o + 8:o + 8 + size]
        nl = min(lines, y1 + 1 - y)
        raw = sum(w * (2 if t == 1 else 4) for _, t in channels) * nl
        if comp != 0 and size < raw:
            d = np.frombuffer(zlib.decompress(data), np.uint8).astype(np.int64)
            d = (np.cumsum(np.concatenate([[d[0]], d[1:] - 128])) & 0xFF).astype(np.uint8)
            half = (len(d) + 1) // 2
            r = np.empty_like(d)
            r[0::2], r[1::2] = d[:half], d[half:]
            data = r.tobytes()
        q = 0
        for line in range(nl):
            for n, t in channels:
                k = w * (2 if t == 1 else 4)
                out[n][y - y0 + line] = np.frombuffer(data[q:q + k], np.float16 if t == 1 else np.float32)
                q += k
    return np.stack([out["R"], out["G"], out["B"]], -1)


def rel_mse(x, r):
    """As bench/compare.py: mean of (x - r)^2 / (r^2 + (0.01 mean(r))^2)."""
    x, r = x.astype(np.float64), r.astype(np.float64)
    eps = max((0.01 * r.mean()) ** 2, np.finfo(float).tiny)
    return float(np.mean((x - r) ** 2 / (r * r + eps)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("ref_a")
    ap.add_argument("ref_b")
    ap.add_argument("--bin", action="append", required=True, help="NAME=PATH of a niebla binary")
    ap.add_argument("--spp", default="4,8,16")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--target", type=float, default=1e-2)
    ap.add_argument("--with-writes", action="store_true",
                    help="time the whole process (checkpoint and final EXR writes included)")
    a = ap.parse_args()
    bins = dict(s.split("=", 1) for s in a.bin)
    ra, rb = read_exr(a.ref_a), read_exr(a.ref_b)
    ref, noise = 0.5 * (ra + rb), rel_mse(ra, rb) / 4
    print(f"reference: own relative MSE {noise:.2e} (subtracted)", flush=True)
    work = tempfile.mkdtemp(prefix="niebla_ttt_")
    desc = json.load(open(a.scene))
    desc["camera"] = dict(desc["camera"], width=8, height=8)
    tiny = os.path.join(work, "tiny.json")
    json.dump(desc, open(tiny, "w"))

    def run(binary, scene, spp, seed):
        out = os.path.join(work, "out.exr")
        cmd = [binary, "render", scene, "--spp", str(spp), "--seed", str(seed), "--threads", str(a.threads),
               "--quiet", "-o", out] + ([] if a.with_writes else ["--no-checkpoints"])
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
        with p.stdout:
            text = p.stdout.read()
        _, status, ru = os.wait4(p.pid, 0)
        assert os.waitstatus_to_exitcode(status) == 0, " ".join(cmd)
        if a.with_writes:
            return out, ru.ru_utime + ru.ru_stime
        m = re.search(r"process CPU ([0-9.]+) s before the final write", text)
        assert m, f"{' '.join(cmd)}: no CPU time in {text!r} (use --with-writes for older binaries)"
        return out, float(m.group(1))

    fixed = {n: min(run(b, tiny, 1, 9 + k)[1] for k in range(2)) for n, b in bins.items()}
    print("fixed CPU s: " + ", ".join(f"{n} {c:.2f}" for n, c in fixed.items()), flush=True)
    points = {n: [] for n in bins}
    for spp in [int(s) for s in a.spp.split(",")]:
        for n, b in bins.items():
            out, cpu = run(b, os.path.abspath(a.scene), spp, 77 + spp)
            e = rel_mse(read_exr(out), ref) - noise
            points[n].append((spp, cpu - fixed[n], e))
            print(f"{n} {spp} spp: CPU {cpu:.2f} s (net {cpu - fixed[n]:.2f}), relative MSE {e:.3e}", flush=True)
    for n, pts in points.items():
        for (s0, c0, e0), (s1, c1, e1) in zip(pts, pts[1:]):
            if e0 >= a.target >= e1 > 0:
                f = (math.log(a.target) - math.log(e0)) / (math.log(e1) - math.log(e0))
                print(f"{n}: {math.exp(math.log(s0) + f * math.log(s1 / s0)):.1f} spp, "
                      f"{math.exp(math.log(c0) + f * math.log(c1 / c0)):.2f} CPU s to relative MSE {a.target:g}")
                break
        else:
            print(f"{n}: the sweep does not bracket {a.target:g}")


if __name__ == "__main__":
    main()
