#!/usr/bin/env python3
"""A million-triangle sphere, to measure what loading and rendering a large mesh costs:

    python3 scripts/make_big_obj.py OUTDIR

writes OUTDIR/big.obj (500 x 1000 rings and segments, 2 triangles each, with vertex normals
and texture coordinates), OUTDIR/flat.obj (the same triangles without them), their MTL and a
scene file for each (big.toml, flat.toml), lit by a point light. Then, for example:

    /usr/bin/time -f "%e s, %M KB" photonmap info OUTDIR/big.toml
"""
import math
import sys
from pathlib import Path

out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
out.mkdir(parents=True, exist_ok=True)
R, S = 500, 1000
with open(out / "big.obj", "w") as f, open(out / "flat.obj", "w") as g:
    for h in (f, g):
        h.write("mtllib big.mtl\nusemtl m\n")
    for i in range(R + 1):
        t = math.pi * i / R
        for j in range(S + 1):
            p = 2 * math.pi * j / S
            x, y, z = math.sin(t) * math.cos(p), math.cos(t), math.sin(t) * math.sin(p)
            f.write(f"v {x:.6f} {y:.6f} {z:.6f}\nvn {x:.6f} {y:.6f} {z:.6f}\nvt {j / S:.6f} {1 - i / R:.6f}\n")
            g.write(f"v {x:.6f} {y:.6f} {z:.6f}\n")
    row = S + 1
    for i in range(R):
        for j in range(S):
            a, b, c, d = i * row + j + 1, i * row + j + 2, (i + 1) * row + j + 2, (i + 1) * row + j + 1
            f.write(f"f {a}/{a}/{a} {c}/{c}/{c} {b}/{b}/{b}\nf {a}/{a}/{a} {d}/{d}/{d} {c}/{c}/{c}\n")
            g.write(f"f {a} {c} {b}\nf {a} {d} {c}\n")
(out / "big.mtl").write_text("newmtl m\nKd 0.5 0.5 0.5\n")
for name in ("big", "flat"):
    (out / f"{name}.toml").write_text(
        "[camera]\neye = [0, 0, 4]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\nvfov_deg = 40\nwidth = 64\nheight = 64\n\n"
        f'[[mesh]]\nobj = "{name}.obj"\n\n[[light]]\ntype = "point"\nposition = [2, 2, 3]\nintensity = [5, 5, 5]\n'
    )
