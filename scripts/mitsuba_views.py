#!/usr/bin/env python3
"""Mitsuba 3's path tracer over the frames of one of our animated cameras: the peer of
`photonmap render --frames` (see scripts/peer-views.sh).

    /work/mitsuba-venv/bin/python scripts/mitsuba_views.py SCENE.toml OUTDIR
        (--seconds S | --frames F,G,... --spp N) [--camera NAME] [--threads T] [--variant V]

Reads our scene with scripts/mitsuba_reference.py's loader (the same exact mapping, or a
refusal; mesh transforms included), takes the camera `--camera` (default: the first) and its
turntable (keyed cameras are refused: their Catmull-Rom curve is not reproduced here), and
builds the Mitsuba scene once. A camera with a thin lens gets `thinlens` sensors (through
mitsuba_reference.sensor_dict); a turntable keeps the lens, as ours does.
Each frame's view is a sensor of its own, rendered with `mi.render(scene, sensor=...)` in one
process, as a user driving Mitsuba from Python would render many views.

--seconds S: every frame of the camera in S seconds in all: the samples per pixel are the most
that fit, from two timing renders (counted in the time), the same for every frame. Writes
OUTDIR/frame_NNNN.exr and prints the time taken.

--frames F,G --spp N: long renders of those frames (references), in batches of 64 spp whose
spread gives the noise left in the mean (as mitsuba_reference.py does); OUTDIR/ref_NNNN.exr
and ref_NNNN.txt.
"""

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mitsuba_reference as ref  # noqa: E402


def rotate(v, axis, angle):
    """Rodrigues' rotation of v about the unit axis by angle (radians)."""
    v, k = np.asarray(v, dtype=np.float64), np.asarray(axis, dtype=np.float64)
    return v * math.cos(angle) + np.cross(k, v) * math.sin(angle) + k * np.dot(k, v) * (1 - math.cos(angle))


def views(camera):
    """[(frame, eye, target, up)] of the camera, as src/scene/camera.rs turns it."""
    eye, target, up = (np.array(camera[k], dtype=np.float64) for k in ("eye", "target", "up"))
    if "key" in camera:
        raise ref.Refused("keyed cameras are not reproduced here (only turntables and still cameras)")
    tt = camera.get("turntable")
    if tt is None:
        return [(0, eye, target, up)]
    n = int(tt["frames"])
    center = np.array(tt.get("center", camera["target"]), dtype=np.float64)
    axis = np.array(tt.get("axis", [0.0, 1.0, 0.0]), dtype=np.float64)
    axis /= np.linalg.norm(axis)
    degrees = float(tt.get("degrees", 360.0))
    out = []
    for f in range(n):
        a = math.radians(degrees * f / n)
        out.append((f, center + rotate(eye - center, axis, a), center + rotate(target - center, axis, a),
                    rotate(up, axis, a)))
    return out


def sensor(mi, camera, eye, target, up, spp):
    return mi.load_dict(ref.sensor_dict(mi, camera, eye, target, up, spp))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", type=Path)
    ap.add_argument("outdir", type=Path)
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--seconds", type=float, help="every frame in this many seconds in all")
    mode.add_argument("--frames", help="comma-separated frames to render as references (with --spp)")
    ap.add_argument("--spp", type=int, default=4096, help="references' samples per pixel")
    ap.add_argument("--camera", help="camera name (default: the first)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()

    import drjit as dr
    import mitsuba as mi

    start = time.perf_counter()
    mi.set_variant(args.variant)
    if args.variant.startswith("llvm"):
        dr.set_thread_count(args.threads)
    try:
        cameras, groups, lights = ref.load_scene(args.scene)
        cameras = cameras if isinstance(cameras, list) else [cameras]
        camera = next((c for c in cameras if args.camera in (None, c.get("name"))), None)
        if camera is None:
            raise ref.Refused(f"no camera named {args.camera!r}")
        frames = views(camera)
    except ref.Refused as e:
        sys.exit(f"{args.scene}: refused: {e}")
    scene = ref.build(mi, camera, groups, lights, 4)
    args.outdir.mkdir(parents=True, exist_ok=True)

    def render(f, spp, seed):
        _, eye, target, up = frames[f]
        img = mi.render(scene, sensor=sensor(mi, camera, eye, target, up, spp), spp=spp, seed=seed)
        return np.array(img, dtype=np.float64)[:, :, :3]

    if args.seconds is not None:
        # Two timing renders (the first compiles the kernels); their time counts.
        probe = 4
        render(0, probe, 1_000_000)
        t0 = time.perf_counter()
        render(len(frames) // 2, probe, 1_000_001)
        per_spp = (time.perf_counter() - t0) / probe
        left = args.seconds - (time.perf_counter() - start)
        spp = max(1, int(left / len(frames) / per_spp))
        for f, *_ in frames:
            ref.write_exr(mi, args.outdir / f"frame_{f:04d}.exr", render(f, spp, f).astype(np.float32))
        wall = time.perf_counter() - start
        print(f"mitsuba {mi.__version__} {args.variant}: {len(frames)} frames at {spp} spp in {wall:.1f} s "
              f"(budget {args.seconds:.1f} s, {60 * len(frames) / wall:.1f} frames/min)")
        return
    batch = 64
    for f in (int(x) for x in args.frames.split(",")):
        t0 = time.perf_counter()
        n = max(2, math.ceil(args.spp / batch))
        total = sq = None
        for b in range(n):
            img = render(f, batch, 10_000 * (f + 1) + b)
            total = img if total is None else total + img
            sq = img * img if sq is None else sq + img * img
        mean = total / n
        var = np.maximum(sq / n - mean * mean, 0.0) * n / (n - 1)
        noise = math.sqrt(var.mean() / n)
        ref.write_exr(mi, args.outdir / f"ref_{f:04d}.exr", mean.astype(np.float32))
        note = (f"frame {f}: {n * batch} spp ({n} batches of {batch}), {time.perf_counter() - t0:.1f} s, "
                f"noise RMSE {noise:.6f}, mean {mean.mean():.6f}")
        (args.outdir / f"ref_{f:04d}.txt").write_text(note + "\n")
        print(note)


if __name__ == "__main__":
    main()
