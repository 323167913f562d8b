#!/usr/bin/env python3
"""Generates the hard test scenes: scenes/<name>/<name>.{toml,obj,mtl}.

    python3 scripts/make_scenes.py [--bunny PATH] [NAME ...]

sunroom    a closed house with thick walls on a 40 m x 40 m ground, lit only by the sun
           (a distant light) through one small window; camera inside.
doorway    two closed rooms joined by a door in a thick shared wall; the ceiling light is in
           room A, the camera in room B (lit only through the door).
bunny      the Stanford bunny (69 451 triangles) in an open-front room, a point light and a
           small ceiling area light.
glassknot  a (2,3) torus knot of glass (IOR 1.5, 20 000 triangles, closed) just above the floor
           of a Cornell room with a small bright light: caustics on the floor.
faraway    the Cornell box x1000, moved to (1e4, -2e4, 3e4) with its camera.
atrium     a two-storey arcaded courtyard (fluted columns, balustrades, banners) open to a black
           sky, one small bright light over it; camera in a lower gallery.

Deterministic, standard library only. Conventions of scenes/SCENES.md: metres, +Y up,
counter-clockwise front faces (n = (v1 - v0) x (v2 - v0)), flat shading (no vn/vt), room walls
facing into the room, closed solids facing outward, diffuse two-sided, emission from the front
side only. Quads are split as (0,1,2),(0,2,3). Closed solids are checked here: every edge is
used by exactly two triangles in opposite directions and the enclosed volume is positive.
"""

import argparse
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"
DEFAULT_BUNNY = Path("/work/shared/data/bunny/stanford-bunny.obj")

# ---------------------------------------------------------------------------------------------
# Vectors (tuples of 3 floats)


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def unit(a):
    n = norm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def fmt(x, digits=6):
    """A number with `digits` significant digits, no negative zero."""
    s = f"{x:.{digits}g}"
    return "0" if s in ("-0", "0") else s


def tomlnum(x):
    """A TOML float, rounded to 12 significant digits (drops arithmetic noise such as 1e-17)."""
    return repr(float(f"{x:.12g}")) if x != 0 else "0.0"


def tomlvec(v):
    return "[" + ", ".join(tomlnum(x) for x in v) + "]"


# ---------------------------------------------------------------------------------------------
# Meshes


class Part:
    """One OBJ object (`o name`) of one material: vertices and triangles (0-based)."""

    def __init__(self, name, material):
        self.name, self.material = name, material
        self.verts, self.tris, self._index = [], [], {}

    def vertex(self, p, share=True):
        if share:
            key = tuple(round(c, 9) for c in p)
            i = self._index.get(key)
            if i is not None:
                return i
            self._index[key] = len(self.verts)
        self.verts.append(tuple(p))
        return len(self.verts) - 1

    def quad(self, p0, p1, p2, p3):
        i = [self.vertex(p) for p in (p0, p1, p2, p3)]
        self.tris += [(i[0], i[1], i[2]), (i[0], i[2], i[3])]

    def normal(self, t):
        a, b, c = (self.verts[k] for k in t)
        return cross(sub(b, a), sub(c, a))


def axis_quad(part, axis, sign, plane, lo, hi):
    """The rectangle {x_axis = plane, lo <= x_other <= hi} facing `sign` along `axis`
    (lo, hi: 3-vectors; their `axis` component is ignored)."""
    b, c = (axis + 1) % 3, (axis + 2) % 3

    def pt(ub, uc):
        p = [0.0, 0.0, 0.0]
        p[axis], p[b], p[c] = plane, ub, uc
        return tuple(p)

    q = [pt(lo[b], lo[c]), pt(hi[b], lo[c]), pt(hi[b], hi[c]), pt(lo[b], hi[c])]  # e_b x e_c = e_axis
    if sign < 0:
        q = [q[0], q[3], q[2], q[1]]
    part.quad(*q)


def grid_solid(xs, ys, zs, solid, material, name):
    """The closed boundary of a union of cells of the rectilinear grid xs x ys x zs.

    solid(centre) says whether a cell is filled; every face between a filled cell and an empty
    one (or the outside of the grid) becomes a quad facing the empty side, its material given by
    material(axis, sign, empty_centre or None). Faces are whole cell faces, so the surface is
    conforming (no T-junctions) and watertight. Returns {material: Part}."""
    g = (xs, ys, zs)
    n = tuple(len(a) - 1 for a in g)

    def centre(idx):
        return tuple(0.5 * (g[a][idx[a]] + g[a][idx[a] + 1]) for a in range(3))

    def inside(idx):
        return all(0 <= idx[a] < n[a] for a in range(3))

    filled = set()
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                if solid(centre((i, j, k))):
                    filled.add((i, j, k))
    parts = {}
    for idx in sorted(filled):
        lo = tuple(g[a][idx[a]] for a in range(3))
        hi = tuple(g[a][idx[a] + 1] for a in range(3))
        for axis in range(3):
            for sign in (-1, 1):
                nb = list(idx)
                nb[axis] += sign
                nb = tuple(nb)
                if nb in filled:
                    continue
                m = material(axis, sign, centre(nb) if inside(nb) else None)
                if m not in parts:
                    parts[m] = Part(f"{name}_{m}", m)
                axis_quad(parts[m], axis, sign, hi[axis] if sign > 0 else lo[axis], lo, hi)
    return parts


def check_closed(parts, what):
    """Every directed edge once, its reverse once (closed, consistently oriented), positive volume."""
    verts, tris = [], []
    index = {}
    for part in parts:
        remap = []
        for p in part.verts:
            key = tuple(round(c, 9) for c in p)
            if key not in index:
                index[key] = len(verts)
                verts.append(p)
            remap.append(index[key])
        tris += [tuple(remap[k] for k in t) for t in part.tris]
    edges = {}
    for t in tris:
        for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            edges[e] = edges.get(e, 0) + 1
    bad = [e for e, k in edges.items() if k != 1 or edges.get((e[1], e[0]), 0) != 1]
    if bad:
        sys.exit(f"{what}: not closed or not consistently oriented ({len(bad)} bad edges, e.g. {bad[:3]})")
    volume = sum(dot(verts[a], cross(verts[b], verts[c])) for a, b, c in tris) / 6.0
    if not volume > 0:
        sys.exit(f"{what}: enclosed volume {volume} is not positive (faces point inward)")
    return volume


# ---------------------------------------------------------------------------------------------
# Materials, files


WHITE = (0.725, 0.71, 0.68)
RED = (0.63, 0.065, 0.05)
GREEN = (0.14, 0.45, 0.091)


def diffuse(kd):
    return {"type": "diffuse", "kd": kd}


def emissive(kd, ke):
    return {"type": "emissive", "kd": kd, "ke": ke}


def glass(ior=1.5):
    return {"type": "glass", "ior": ior}


def glossy(kd, ks, ns):
    return {"type": "glossy", "kd": kd, "ks": ks, "ns": ns}


def principled(base, metallic, roughness):
    return {"type": "principled", "kd": base, "metallic": metallic, "roughness": roughness}


def write_mtl(path, materials):
    out = [
        "# generated by scripts/make_scenes.py. Material TYPE is authoritative in the .toml sidecar.",
        "# diffuse: illum 1 (Kd); mirror: illum 3 (Ks=1, Kd=0); glass: illum 7 (Ks=1, Tf=1, Ni);",
        "# emissive: illum 1 with Kd (albedo) and Ke (radiance W/m^2/sr, front side only).",
    ]
    for name, m in materials.items():
        out.append("")
        out.append(f"newmtl {name}")
        v = lambda t: " ".join(fmt(x) for x in t)  # noqa: E731
        if m["type"] == "glass":
            out += ["Kd 0 0 0", "Ks 1 1 1", "Tf 1 1 1", f"Ni {fmt(m['ior'])}", "Ke 0 0 0", "illum 7"]
        elif m["type"] == "mirror":
            out += ["Kd 0 0 0", "Ks 1 1 1", "Ke 0 0 0", "illum 3"]
        elif m["type"] == "glossy":
            out += [f"Kd {v(m['kd'])}", f"Ks {v(m['ks'])}", f"Ns {fmt(m['ns'])}", "Ke 0 0 0", "illum 2"]
        elif m["type"] == "principled":
            out += [f"Kd {v(m['kd'])}", f"Pr {fmt(m['roughness'])}", f"Pm {fmt(m['metallic'])}", "Ke 0 0 0",
                    "illum 2"]
        else:
            out += [f"Kd {v(m['kd'])}", "Ks 0 0 0", f"Ke {v(m.get('ke', (0, 0, 0)))}", "illum 1"]
    path.write_text("\n".join(out) + "\n")


def write_obj(path, parts, mtl_name, comments=(), digits=6):
    out = ["# generated by scripts/make_scenes.py -- units metres, right-handed, +Y up"]
    out += [f"# {c}" for c in comments]
    out += ["# flat shading: no vn/vt. Triangles CCW around their geometric normal.", f"mtllib {mtl_name}"]
    base = 1
    for part in parts:
        out.append(f"o {part.name}")
        out += [f"v {fmt(p[0], digits)} {fmt(p[1], digits)} {fmt(p[2], digits)}" for p in part.verts]
        out.append(f"usemtl {part.material}")
        out += [f"f {a + base} {b + base} {c + base}" for a, b, c in part.tris]
        base += len(part.verts)
    path.write_text("\n".join(out) + "\n")


def write_toml(path, name, description, triangles, camera, materials, lights=(), notes=()):
    out = [
        "# generated by scripts/make_scenes.py -- conventions in scenes/SCENES.md",
        f"# {name}: {description}",
        "# units metres, right-handed, +Y up, flat shading, diffuse two-sided, emission front side "
        f"only; {triangles} triangles",
        "# reference transport: max_depth = -1 (-1: unlimited)",
    ]
    out += [f"# {n}" for n in notes]
    out += [
        "",
        "[camera]",
        f"eye = {tomlvec(camera['eye'])}",
        f"target = {tomlvec(camera['target'])}",
        f"up = {tomlvec(camera.get('up', (0.0, 1.0, 0.0)))}",
        f"vfov_deg = {tomlnum(camera['vfov_deg'])}  # full vertical field of view",
        "width = 256",
        "height = 256",
        "",
        "[[mesh]]",
        f'obj = "{name}.obj"',
    ]
    for mname, m in materials.items():
        out += ["", f"[materials.{mname}]", f'type = "{m["type"]}"']
        if m["type"] in ("diffuse", "emissive", "glossy", "principled"):
            out.append(f"kd = {tomlvec(m['kd'])}")
        if m["type"] == "principled":
            out.append(f"metallic = {tomlnum(m['metallic'])}")
            out.append(f"roughness = {tomlnum(m['roughness'])}  # glTF's: GGX alpha = roughness^2")
        if m["type"] == "glossy":
            out.append(f"ks = {tomlvec(m['ks'])}")
            out.append(f"ns = {tomlnum(m['ns'])}  # normalised Phong exponent")
        if m["type"] == "emissive":
            out.append(f"ke = {tomlvec(m['ke'])}  # radiance, W m^-2 sr^-1")
        if m["type"] == "glass":
            out.append(f"ior = {tomlnum(m['ior'])}")
    for light in lights:
        out += ["", "[[light]]", f'type = "{light["type"]}"']
        if light["type"] == "point":
            out.append(f"position = {tomlvec(light['position'])}")
            out.append(f"intensity = {tomlvec(light['intensity'])}  # W/sr, isotropic")
        elif light["type"] == "distant":
            out.append(f"direction = {tomlvec(light['direction'])}  # the way the light travels")
            out.append(f"irradiance = {tomlvec(light['irradiance'])}  # W/m^2 on a surface facing the light")
        else:
            raise ValueError(light["type"])
    path.write_text("\n".join(out) + "\n")


def emit(name, description, parts, materials, camera, lights=(), notes=(), obj_comments=(), digits=6):
    d = SCENES / name
    d.mkdir(parents=True, exist_ok=True)
    used = {p.material for p in parts}
    materials = {k: v for k, v in materials.items() if k in used}
    triangles = sum(len(p.tris) for p in parts)
    write_obj(d / f"{name}.obj", parts, f"{name}.mtl", obj_comments, digits)
    write_mtl(d / f"{name}.mtl", materials)
    write_toml(d / f"{name}.toml", name, description, triangles, camera, materials, lights, notes)
    print(f"{name}: {triangles} triangles, {sum(len(p.verts) for p in parts)} vertices")
    return triangles


def room_quad(name, material, axis, sign, plane, lo, hi):
    p = Part(name, material)
    axis_quad(p, axis, sign, plane, lo, hi)
    return p


# ---------------------------------------------------------------------------------------------
# sunroom


def sunroom():
    t = 0.15  # wall thickness
    ix, iz = (-2.0, 2.0), (-1.5, 1.5)  # interior, floor at y = 0.15, ceiling at 2.65
    floor_y, ceil_y = 0.15, 2.65
    win_x, win_y = (0.05, 0.55), (1.15, 1.75)  # 0.5 m x 0.6 m, in the +Z wall
    xs = [ix[0] - t, ix[0], win_x[0], win_x[1], ix[1], ix[1] + t]
    ys = [-0.1, floor_y, win_y[0], win_y[1], ceil_y, ceil_y + 0.2]
    zs = [iz[0] - t, iz[0], iz[1], iz[1] + t]

    def interior(p):
        return ix[0] < p[0] < ix[1] and floor_y < p[1] < ceil_y and iz[0] < p[2] < iz[1]

    def window(p):
        return win_x[0] < p[0] < win_x[1] and win_y[0] < p[1] < win_y[1] and p[2] > iz[1]

    def solid(p):
        return not interior(p) and not window(p)

    def material(axis, sign, empty):
        if empty is None:
            return "exterior"
        if interior(empty) and axis == 1:
            return "floor" if sign > 0 else "ceiling"
        return "wall"  # inside walls and the window's reveals

    house = grid_solid(xs, ys, zs, solid, material, "house")
    parts = [house[m] for m in ("floor", "wall", "ceiling", "exterior")]
    volume = check_closed(parts, "sunroom house")
    g = 20.0
    ground = room_quad("ground", "ground", 1, 1, 0.0, (-g, 0, -g), (g, 0, g))
    parts.append(ground)

    elev, azim = math.radians(40.0), math.radians(20.0)
    to_sun = (math.cos(elev) * math.sin(azim), math.sin(elev), math.cos(elev) * math.cos(azim))
    direction = tuple(-c for c in to_sun)

    # Share of the distant light's photons (emitted uniformly over the disc covering the scene's
    # bounding sphere, src/light/distant.rs) that pass through the window: the window's opening
    # through the thick wall projected along the sun, over the disc's area.
    lo = (-g, -0.1, -g)
    hi = (g, ceil_y + 0.2, g)
    radius = 0.5 * norm(sub(hi, lo))
    shift_x = t * abs(direction[0] / direction[2])
    shift_y = t * abs(direction[1] / direction[2])
    through = max(0.0, win_x[1] - win_x[0] - shift_x) * max(0.0, win_y[1] - win_y[0] - shift_y)
    projected = through * abs(direction[2])
    fraction = projected / (math.pi * radius**2)

    materials = {
        "floor": diffuse((0.55, 0.4, 0.25)),
        "wall": diffuse(WHITE),
        "ceiling": diffuse((0.75, 0.75, 0.75)),
        "exterior": diffuse((0.5, 0.5, 0.5)),
        "ground": diffuse((0.3, 0.35, 0.2)),
    }
    camera = {"eye": (1.75, 1.55, -1.35), "target": (-0.05, 0.75, 0.65), "vfov_deg": 62.0}
    lights = [{"type": "distant", "direction": direction, "irradiance": (8.0, 7.5, 7.0)}]
    notes = [
        f"house: closed solid (walls {t} m thick, {volume:.3f} m^3), interior x [-2, 2], y [0.15, 2.65], "
        "z [-1.5, 1.5]; window x [0.05, 0.55], y [1.15, 1.75] in the +Z wall",
        "sun: 40 deg elevation, 20 deg azimuth from +Z towards +X; ground 40 m x 40 m at y = 0, no sky",
        f"share of sun photons through the window (opening projected along the sun / disc over the "
        f"bounding sphere, R = {radius:.3f} m): {projected:.4f} / {math.pi * radius**2:.1f} m^2 "
        f"= {fraction:.3g} (1 in {1 / fraction:.0f})",
    ]
    desc = ("closed house (thick walls, separate inside and outside surfaces) on a large ground, lit "
            "only by the sun (distant light) through one 0.5 m x 0.6 m window; camera inside, "
            "looking at the sun patch on the floor and the bounce-lit walls.")
    emit("sunroom", desc, parts, materials, camera, lights, notes)
    print(f"  sun photons through the window: {fraction:.3g} (1 in {1 / fraction:.0f})")


# ---------------------------------------------------------------------------------------------
# doorway


def doorway():
    t = 0.15
    wall = (-0.075, 0.075)  # the shared wall
    room_a, room_b = (-3.075, wall[0]), (wall[1], 3.075)
    iz, iy = (-1.5, 1.5), (0.0, 2.5)
    door_z, door_top = (0.05, 0.95), 2.0  # 0.9 m x 2.0 m
    xs = [room_a[0] - t, room_a[0], wall[0], wall[1], room_b[1], room_b[1] + t]
    ys = [iy[0] - t, iy[0], door_top, iy[1], iy[1] + t]
    zs = [iz[0] - t, iz[0], door_z[0], door_z[1], iz[1], iz[1] + t]

    def in_room(p, r):
        return r[0] < p[0] < r[1] and iy[0] < p[1] < iy[1] and iz[0] < p[2] < iz[1]

    def door(p):
        return wall[0] < p[0] < wall[1] and iy[0] < p[1] < door_top and door_z[0] < p[2] < door_z[1]

    def solid(p):
        return not (in_room(p, room_a) or in_room(p, room_b) or door(p))

    def material(axis, sign, empty):
        if empty is None:
            return "exterior"
        if axis == 1 and not door(empty):
            return "floor" if sign > 0 else "ceiling"
        if axis == 0 and sign > 0 and in_room(empty, room_a):
            return "red"  # the far wall of room A
        if axis == 2 and sign < 0 and in_room(empty, room_b):
            return "blue"  # the +Z wall of room B
        return "wall"

    shell = grid_solid(xs, ys, zs, solid, material, "rooms")
    parts = [shell[m] for m in ("floor", "ceiling", "wall", "red", "blue", "exterior")]
    volume = check_closed(parts, "doorway shell")
    cx, cz, h = -1.575, 0.0, 0.3  # light: 0.6 m x 0.6 m, centred in room A, 1 mm below the ceiling
    light = room_quad("light", "light", 1, -1, iy[1] - 0.001, (cx - h, 0, cz - h), (cx + h, 0, cz + h))
    parts.append(light)
    materials = {
        "floor": diffuse((0.5, 0.45, 0.4)),
        "ceiling": diffuse((0.75, 0.75, 0.75)),
        "wall": diffuse(WHITE),
        "red": diffuse(RED),
        "blue": diffuse((0.1, 0.2, 0.5)),
        "exterior": diffuse((0.5, 0.5, 0.5)),
        "light": emissive((0.78, 0.78, 0.78), (20.0, 18.0, 15.0)),
    }
    camera = {"eye": (2.85, 1.5, -1.3), "target": (0.0, 1.0, 0.5), "vfov_deg": 60.0}
    notes = [
        f"one closed solid ({volume:.3f} m^3 of wall, 0.15 m thick): room A x [-3.075, -0.075], room B x "
        "[0.075, 3.075], both y [0, 2.5], z [-1.5, 1.5]",
        "door in the shared wall x [-0.075, 0.075]: z [0.05, 0.95], y [0, 2.0]; light 0.6 m x 0.6 m "
        "in room A's ceiling, facing down",
    ]
    desc = ("two closed rooms joined by a door in a 0.15 m shared wall; ceiling area light in room A "
            "only; camera in room B, whose walls are lit only through the door.")
    emit("doorway", desc, parts, materials, camera, (), notes)


# ---------------------------------------------------------------------------------------------
# bunny


def read_bunny(path):
    verts, tris = [], []
    for line in path.read_text().splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            verts.append(tuple(float(x) for x in w[1:4]))
        elif w[0] == "f":
            idx = [int(x.split("/")[0]) for x in w[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            for k in range(1, len(idx) - 1):
                tris.append((idx[0], idx[k], idx[k + 1]))
    return verts, tris


def bunny(bunny_path):
    verts, tris = read_bunny(bunny_path)
    scale, rot = 3.0, math.radians(-20.0)  # rotated about +Y to turn its face a little to the camera
    lo = [min(v[a] for v in verts) for a in range(3)]
    hi = [max(v[a] for v in verts) for a in range(3)]
    base = (0.5 * (lo[0] + hi[0]), lo[1], 0.5 * (lo[2] + hi[2]))
    place = (0.0, 0.0005, 0.1)  # bottom 0.5 mm above the floor
    c, s = math.cos(rot), math.sin(rot)
    part = Part("bunny", "bunny_white")
    for v in verts:
        x, y, z = mul(sub(v, base), scale)
        part.vertex((c * x + s * z + place[0], y + place[1], -s * x + c * z + place[2]), share=False)
    part.tris = list(tris)
    degenerate = sum(1 for t in tris if norm(part.normal(t)) == 0.0)
    x0, x1, y1, z0, z1 = -0.6, 0.6, 1.0, -0.6, 0.6  # open front at z = -0.6
    room = [
        room_quad("floor", "white", 1, 1, 0.0, (x0, 0, z0), (x1, 0, z1)),
        room_quad("ceiling", "white", 1, -1, y1, (x0, 0, z0), (x1, 0, z1)),
        room_quad("back_wall", "white", 2, -1, z1, (x0, 0, 0), (x1, y1, 0)),
        room_quad("left_wall_blue", "blue", 0, -1, x1, (0, 0, z0), (0, y1, z1)),
        room_quad("right_wall_yellow", "yellow", 0, 1, x0, (0, 0, z0), (0, y1, z1)),
    ]
    lx, lz, h = 0.15, 0.2, 0.1  # light: 0.2 m x 0.2 m, 1 mm below the ceiling
    room.append(room_quad("light", "light", 1, -1, y1 - 0.001, (lx - h, 0, lz - h), (lx + h, 0, lz + h)))
    parts = room + [part]
    materials = {
        "white": diffuse(WHITE),
        "blue": diffuse((0.15, 0.25, 0.6)),
        "yellow": diffuse((0.7, 0.55, 0.15)),
        "light": emissive((0.78, 0.78, 0.78), (18.0, 16.0, 13.0)),
        "bunny_white": diffuse((0.8, 0.8, 0.8)),
    }
    camera = {"eye": (0.0, 0.5, -1.9), "target": (0.0, 0.34, 0.1), "vfov_deg": 32.0}
    lights = [{"type": "point", "position": (-0.35, 0.75, -0.3), "intensity": (0.3, 0.28, 0.25)}]
    h_bunny = (hi[1] - lo[1]) * scale
    notes = [
        f"bunny: Stanford bun_zipper ({len(tris)} triangles, {degenerate} of zero area, as published), "
        f"scaled x{scale:g} ({h_bunny:.3f} m tall), turned {math.degrees(rot):g} deg about +Y, on the floor "
        "at (0, 0, 0.1); provenance and terms (research use, no commercial use) in SOURCE.md",
        "room x [-0.6, 0.6], y [0, 1], z [-0.6, 0.6], open at z = -0.6; light 0.2 m x 0.2 m in the ceiling; "
        "point light front left",
    ]
    comments = [
        "bunny: the Stanford bunny (bun_zipper), Stanford Computer Graphics Laboratory, see SOURCE.md",
        "(research use with acknowledgement; no commercial use without Stanford's permission)",
    ]
    desc = ("the Stanford bunny (scanned mesh, 69451 triangles) on the floor of an open-front room, "
            "lit by a point light and a small ceiling area light.")
    emit("bunny", desc, parts, materials, camera, lights, notes, comments)


# ---------------------------------------------------------------------------------------------
# glassknot


def read_cornell_room():
    """The Cornell room's objects from scenes/cornell/cornell.obj (vertices as published)."""
    objects, current, verts = [], None, []
    for line in (SCENES / "cornell" / "cornell.obj").read_text().splitlines():
        w = line.split()
        if not w:
            continue
        if w[0] == "o":
            current = {"name": w[1], "material": None, "tris": []}
            objects.append(current)
        elif w[0] == "v":
            verts.append(tuple(float(x) for x in w[1:4]))
        elif w[0] == "usemtl":
            current["material"] = w[1]
        elif w[0] == "f":
            idx = [int(x) - 1 for x in w[1:]]
            for k in range(1, len(idx) - 1):
                current["tris"].append((idx[0], idx[k], idx[k + 1]))
    parts = []
    for o in objects:
        p = Part(o["name"], o["material"])
        for t in o["tris"]:
            i = [p.vertex(verts[k], share=False) for k in t]
            p.tris.append(tuple(i))
        parts.append(p)
    return parts


def torus_knot(n_u, n_v, tube, scale, offset, p=2, q=3):
    """A (p, q) torus knot tube: centre line ((2 + cos qt) cos pt, (2 + cos qt) sin pt, -sin qt)
    (knot units) with its main plane laid horizontal, a circle of radius `tube` swept along it
    on a rotation-minimising frame (the closing twist spread evenly), n_u rings of n_v vertices."""

    def curve(t):
        r = 2.0 + math.cos(q * t)
        return (r * math.cos(p * t), r * math.sin(p * t), -math.sin(q * t))

    def tangent(t):
        r, dr = 2.0 + math.cos(q * t), -q * math.sin(q * t)
        return unit((dr * math.cos(p * t) - r * p * math.sin(p * t),
                     dr * math.sin(p * t) + r * p * math.cos(p * t), -q * math.cos(q * t)))

    ts = [2.0 * math.pi * i / n_u for i in range(n_u + 1)]
    tan = [tangent(t) for t in ts]
    normals = [unit(cross(tan[0], (0.0, 0.0, 1.0)))]
    for i in range(1, n_u + 1):
        nrm = normals[-1]
        nrm = sub(nrm, mul(tan[i], dot(nrm, tan[i])))  # project onto the new normal plane
        normals.append(unit(nrm))
    # Closing twist: angle from normals[0] to the transported normals[n_u] about tan[0].
    twist = math.atan2(dot(cross(normals[0], normals[n_u]), tan[0]), dot(normals[0], normals[n_u]))
    part = Part("knot", "glass")
    for i in range(n_u):
        a = -twist * i / n_u
        n0, b0 = normals[i], cross(tan[i], normals[i])
        nrm = add(mul(n0, math.cos(a)), mul(b0, math.sin(a)))
        bin_ = cross(tan[i], nrm)
        c = curve(ts[i])
        for j in range(n_v):
            th = 2.0 * math.pi * j / n_v
            k = add(c, add(mul(nrm, tube * math.cos(th)), mul(bin_, tube * math.sin(th))))
            # knot (x, y, z) -> world (x, z, y): main plane horizontal
            part.vertex((k[0] * scale + offset[0], k[2] * scale + offset[1], k[1] * scale + offset[2]),
                        share=False)
    for i in range(n_u):
        for j in range(n_v):
            a, b = i * n_v + j, ((i + 1) % n_u) * n_v + j
            c, d = ((i + 1) % n_u) * n_v + (j + 1) % n_v, i * n_v + (j + 1) % n_v
            part.tris += [(a, b, c), (a, c, d)]
    # Outward: flip every triangle if the enclosed volume comes out negative.
    vol = sum(dot(part.verts[a], cross(part.verts[b], part.verts[c])) for a, b, c in part.tris)
    if vol < 0:
        part.tris = [(a, c, b) for a, b, c in part.tris]
    return part


def strand_gap(n, p=2, q=3):
    """Closest approach of two strands of the knot's centre line (knot units): the least distance
    between samples more than 2.5 units of arc apart (the radius of curvature is at least 1.43,
    so nearer samples lie on the same strand)."""
    pts = [((2 + math.cos(q * t)) * math.cos(p * t), (2 + math.cos(q * t)) * math.sin(p * t), -math.sin(q * t))
           for t in (2 * math.pi * i / n for i in range(n))]
    arc = [norm(sub(pts[(i + 1) % n], pts[i])) for i in range(n)]
    step = sum(arc) / n
    best = math.inf
    for i in range(n):
        for j in range(i + 1, n):
            if min(j - i, n - j + i) * step > 2.5:
                best = min(best, norm(sub(pts[i], pts[j])))
    return best


def glassknot():
    room = [p for p in read_cornell_room() if p.material != "light" and "block" not in p.name]
    tube, scale = 0.45, 0.0435
    height = 1.0 + tube  # knot units above the knot's centre plane
    centre = (0.278, 0.003 + height * scale, 0.28)  # lowest point 3 mm above the floor
    knot = torus_knot(500, 20, tube, scale, centre)
    volume = check_closed([knot], "glass knot")
    low = min(v[1] for v in knot.verts)
    gap = strand_gap(600) - 2.0 * tube
    if not gap > 0:
        sys.exit(f"glass knot: the tube intersects itself (strand gap {gap})")
    cx, cz, h = 0.278, 0.2796, 0.04  # light 0.08 m x 0.08 m, 0.5 mm below the ceiling (as cornell's)
    light = room_quad("light", "light", 1, -1, 0.5483, (cx - h, 0, cz - h), (cx + h, 0, cz + h))
    parts = room + [light, knot]
    materials = {
        "white": diffuse(WHITE),
        "red": diffuse(RED),
        "green": diffuse(GREEN),
        "light": emissive((0.78, 0.78, 0.78), (40.0, 36.0, 30.0)),
        "glass": glass(1.5),
    }
    camera = {"eye": (0.278, 0.45, -0.45), "target": (0.278, 0.07, 0.3), "vfov_deg": 35.0}
    notes = [
        f"knot: (2,3) torus knot, centre line ((2 + cos 3t) cos 2t, -sin 3t, (2 + cos 3t) sin 2t) x {scale} m "
        f"+ ({centre[0]}, {centre[1]:.6g}, {centre[2]}), tube radius {tube * scale:.5f} m, 500 x 20 quads, "
        f"closed, outward ({volume * 1e6:.1f} cm^3), lowest point {low * 1000:.2f} mm above the floor, "
        f"strands at least {gap * scale * 1000:.1f} mm apart",
        "room: cornell's (walls, floor, ceiling as published); light 0.08 m x 0.08 m centred under the ceiling",
    ]
    desc = ("a glass (IOR 1.5) (2,3) torus knot of 20000 flat triangles just above the floor of the "
            "Cornell room, small bright ceiling light: caustics on the floor.")
    emit("glassknot", desc, parts, materials, camera, (), notes)


def uv_sphere(part, centre, r, n_lat, n_lon):
    """A closed sphere of flat triangles: `n_lat` bands of `n_lon` quads, facing outward."""
    def p(i, j):
        t, f = math.pi * i / n_lat, math.tau * j / n_lon
        return add(centre, (r * math.sin(t) * math.cos(f), r * math.cos(t), -r * math.sin(t) * math.sin(f)))

    for i in range(n_lat):
        for j in range(n_lon):
            a, b, c, d = p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)
            if i == 0:
                part.tris.append(tuple(part.vertex(q) for q in (a, b, c)))
            elif i == n_lat - 1:
                part.tris.append(tuple(part.vertex(q) for q in (a, b, d)))
            else:
                part.quad(a, b, c, d)


def shiny_room(name, desc, shiny, notes):
    # The Cornell room with a floor, the two blocks and a ball on the short one of the materials
    # `shiny` names ("floor", "tall", "short", "ball"), lit by the room's ceiling light.
    room = read_cornell_room()
    for p in room:
        if p.name.startswith("floor"):
            p.material = shiny["floor"][0]
        elif "tall" in p.name:
            p.material = shiny["tall"][0]
        elif "short" in p.name:
            p.material = shiny["short"][0]
    ball = Part("ball", shiny["ball"][0])
    uv_sphere(ball, (0.186, 0.165 + 0.0701, 0.169), 0.07, 48, 96)
    check_closed([ball], "ball")
    materials = {
        "white": diffuse(WHITE),
        "red": diffuse(RED),
        "green": diffuse(GREEN),
        "light": emissive((0.78, 0.78, 0.78), (17.0, 12.0, 4.0)),
    }
    materials.update(dict(shiny.values()))
    camera = {"eye": (0.278, 0.273, -0.8), "target": (0.278, 0.273, 0.0), "vfov_deg": 39.30764811610662}
    emit(name, desc, room + [ball], materials, camera, (), notes)


def glossyroom():
    # The Cornell room with glossy (normalised Phong) surfaces of the kinds glTF models bring:
    # a rough gold-like metal block, a blue plastic block (4 % sharp coat), a sharp metal
    # sphere and a glossy floor, lit by the room's ceiling light.
    shiny = {
        "floor": ("floor", glossy((0.45, 0.44, 0.42), (0.25, 0.25, 0.25), 30.0)),
        "tall": ("gold", glossy((0.0, 0.0, 0.0), (0.9, 0.72, 0.4), 60.0)),
        "short": ("plastic", glossy((0.1, 0.24, 0.58), (0.04, 0.04, 0.04), 400.0)),
        "ball": ("chrome", glossy((0.0, 0.0, 0.0), (0.85, 0.85, 0.85), 2000.0)),
    }
    notes = [
        "room: cornell's as published; floor glossy, tall block rough gold-like metal (kd 0, ns 60), "
        "short block blue plastic (ks 0.04, ns 400), ball: flat 48 x 96 sphere of radius 0.07 m on the "
        "short block, sharp metal (ns 2000)",
    ]
    desc = ("the Cornell box with glossy normalised-Phong surfaces: glossy floor, rough metal and "
            "plastic blocks, a sharp metal ball.")
    shiny_room("glossyroom", desc, shiny, notes)


def pbrroom():
    # The glossy room's geometry with glTF's metallic-roughness materials (GGX, Schlick's
    # Fresnel), the kinds a glTF model brings: a rough dielectric floor (its lobe estimated from
    # the photons), a rough gold block, a smooth blue plastic block and a polished metal ball
    # (their lobes traced).
    shiny = {
        "floor": ("floor", principled((0.6, 0.58, 0.55), 0.0, 0.45)),
        "tall": ("gold", principled((1.0, 0.78, 0.34), 1.0, 0.5)),
        "short": ("plastic", principled((0.1, 0.25, 0.6), 0.0, 0.25)),
        "ball": ("steel", principled((0.95, 0.93, 0.88), 1.0, 0.15)),
    }
    notes = [
        "room: cornell's as published; floor a rough dielectric (roughness 0.45), tall block rough gold "
        "(metallic 1, roughness 0.5), short block blue plastic (metallic 0, roughness 0.25), ball: flat "
        "48 x 96 sphere of radius 0.07 m on the short block, polished steel (metallic 1, roughness 0.15)",
    ]
    desc = ("the Cornell box with glTF metallic-roughness surfaces: rough dielectric floor, rough gold "
            "and smooth plastic blocks, a polished metal ball.")
    shiny_room("pbrroom", desc, shiny, notes)


# ---------------------------------------------------------------------------------------------
# atrium


def box(part, lo, hi):
    """The closed boundary of the box [lo, hi], facing outward."""
    for axis in range(3):
        axis_quad(part, axis, -1, lo[axis], lo, hi)
        axis_quad(part, axis, 1, hi[axis], lo, hi)


def fluted_column(part, cx, cz, r, y0, y1, sides=48, flutes=16, depth=0.06):
    """A closed prism of `sides` sides around the vertical axis through (cx, cz), its radius
    r (1 - depth (1 + cos(flutes a)) / 2): shallow flutes, as a classical column's."""
    def p(k, y):
        a = math.tau * k / sides
        rr = r * (1.0 - depth * 0.5 * (1.0 + math.cos(flutes * a)))
        return (cx + rr * math.cos(a), y, cz + rr * math.sin(a))

    bottom, top = part.vertex((cx, y0, cz)), part.vertex((cx, y1, cz))
    for k in range(sides):
        part.quad(p(k + 1, y0), p(k, y0), p(k, y1), p(k + 1, y1))
        a0, a1 = part.vertex(p(k, y0)), part.vertex(p(k + 1, y0))
        b0, b1 = part.vertex(p(k, y1)), part.vertex(p(k + 1, y1))
        part.tris += [(top, b1, b0), (bottom, a0, a1)]


def atrium():
    # A courtyard 14 m x 5 m open to a black sky, two storeys of arcades along its long sides
    # with galleries behind: fluted columns below, pillars and balustrades above, banners
    # hanging in the lower arches; one small bright light over the courtyard. Most surfaces the
    # camera sees are lit by bounced light, in galleries, behind columns and between balusters
    # whose size is that of a gather disc or less.
    bays = [-5.0, -3.0, -1.0, 1.0, 3.0, 5.0]  # pillar and column centres along x
    half = 0.25  # upper pillars 0.5 m wide
    xs = [-7.3, -7.0] + [v for c in bays for v in (c - half, c + half)] + [7.0, 7.3]
    ys = [-0.3, 0.0, 3.2, 4.0, 4.3, 7.0, 8.0, 8.3]
    zs = [-5.1, -4.8, -2.8, -2.5, 2.5, 2.8, 4.8, 5.1]

    def pillar(x):
        return any(abs(x - c) < half for c in bays)

    def solid(p):
        x, y, z = p
        az = abs(z)
        if y < 0.0 or abs(x) > 7.0 or az > 4.8:
            return True  # floor slab, end walls, back walls
        if 2.5 < az < 2.8:  # the arcades: lintel bands, upper pillars; columns below are apart
            return y > 3.2 and not (4.3 < y < 7.0 and not pillar(x))
        if az > 2.8:  # the galleries: the upper floor and the roof
            return 4.0 < y < 4.3 or 8.0 < y < 8.3
        return False  # the courtyard

    def material(axis, sign, empty):
        if empty is None:
            return "exterior"
        if axis == 1:
            return "floor" if sign > 0 else "ceiling"
        return "stone"

    shell = grid_solid(xs, ys, zs, solid, material, "atrium")
    parts = [shell[m] for m in ("floor", "ceiling", "stone", "exterior")]
    volume = check_closed(parts, "atrium shell")

    columns = Part("columns", "column")
    for c in bays:
        for zc in (-2.65, 2.65):
            piece = Part("column", "column")
            box(piece, (c - 0.3, -0.05, zc - 0.3), (c + 0.3, 0.25, zc + 0.3))  # plinth
            check_closed([piece], "plinth")
            shaft = Part("shaft", "column")
            fluted_column(shaft, c, zc, 0.22, 0.2, 2.95)
            check_closed([shaft], "column shaft")
            cap = Part("capital", "column")
            box(cap, (c - 0.3, 2.9, zc - 0.3), (c + 0.3, 3.21, zc + 0.3))
            for q in (piece, shaft, cap):
                base = len(columns.verts)
                columns.verts += q.verts
                columns.tris += [(a + base, b + base, d + base) for a, b, d in q.tris]

    # Balustrades in the upper arches: balusters 7 cm square every 18 cm, a rail on top.
    rails = Part("balustrades", "column")
    edges = [-7.0] + [v for c in bays for v in (c - half, c + half)] + [7.0]
    balusters = 0
    for lo_x, hi_x in zip(edges[0::2], edges[1::2]):
        n = int((hi_x - lo_x) / 0.18)
        step = (hi_x - lo_x) / n
        for zc in (-2.65, 2.65):
            q = Part("rail", "column")
            box(q, (lo_x - 0.01, 5.1, zc - 0.1), (hi_x + 0.01, 5.22, zc + 0.1))
            parts_here = [q]
            for k in range(1, n):
                x = lo_x + k * step
                b = Part("baluster", "column")
                box(b, (x - 0.035, 4.29, zc - 0.035), (x + 0.035, 5.11, zc + 0.035))
                parts_here.append(b)
                balusters += 1
            for b in parts_here:
                base = len(rails.verts)
                rails.verts += b.verts
                rails.tris += [(a + base, bb + base, d + base) for a, bb, d in b.tris]

    # Banners: single sheets (two-sided) hanging in front of every other lower arch.
    banners = {m: Part(f"banner_{m}", m) for m in ("banner_red", "banner_blue")}
    for i, (lo_x, hi_x) in enumerate(zip(edges[0::2], edges[1::2])):
        if i % 2 == 1:
            continue
        for zc, m in ((-2.45, "banner_red"), (2.45, "banner_blue")):
            axis_quad(banners[m], 2, 1 if zc < 0 else -1, zc, (lo_x + 0.25, 1.3, 0), (hi_x - 0.25, 3.19, 0))

    cx, cy, cz, h = 0.6, 6.5, 0.2, 0.2  # light: 0.4 m x 0.4 m over the courtyard, facing down
    light = room_quad("light", "light", 1, -1, cy, (cx - h, 0, cz - h), (cx + h, 0, cz + h))
    parts += [columns, rails, light] + [banners[m] for m in ("banner_red", "banner_blue")]
    materials = {
        "floor": diffuse((0.55, 0.5, 0.42)),
        "ceiling": diffuse((0.7, 0.66, 0.58)),
        "stone": diffuse((0.72, 0.62, 0.46)),
        "exterior": diffuse((0.5, 0.5, 0.5)),
        "column": diffuse((0.78, 0.75, 0.68)),
        "banner_red": diffuse((0.6, 0.08, 0.06)),
        "banner_blue": diffuse((0.1, 0.16, 0.5)),
        "light": emissive((0.78, 0.78, 0.78), (400.0, 380.0, 330.0)),
    }
    camera = {"eye": (-6.5, 1.7, -3.9), "target": (2.0, 2.4, 0.6), "vfov_deg": 70.0}
    notes = [
        f"shell: one closed solid ({volume:.3f} m^3): floor y [-0.3, 0], end walls |x| > 7, back walls "
        "|z| > 4.8, arcades |z| in [2.5, 2.8] (lintels from y 3.2, upper pillars 0.5 m wide at "
        "x = -5, -3, ..., 5, upper arches y [4.3, 7]), gallery floors y [4, 4.3], roofs y [8, 8.3]; "
        "the courtyard |x| < 7, |z| < 2.5 is open above (black sky)",
        f"12 fluted columns (48 sides, r 0.22 m) on plinths under capitals; {balusters} balusters "
        "(7 cm square, 0.82 m) and rails in the upper arches; banners: single two-sided sheets "
        "in front of every other lower arch",
        f"light: 0.4 m x 0.4 m at y = {cy}, centred at x {cx}, z {cz}, facing down",
    ]
    desc = ("a two-storey arcaded courtyard (fluted columns, balustrades, banners) open to a black "
            "sky, one small bright light over it; camera in a lower gallery: mostly bounced light.")
    emit("atrium", desc, parts, materials, camera, (), notes)


# ---------------------------------------------------------------------------------------------
# faraway


def faraway():
    scale, move = 1000.0, (1.0e4, -2.0e4, 3.0e4)
    parts = []
    for p in read_cornell_room():
        q = Part(p.name, p.material)
        q.verts = [add(mul(v, scale), move) for v in p.verts]
        q.tris = p.tris
        parts.append(q)
    cam = {"eye": (0.278, 0.273, -0.8), "target": (0.278, 0.273, 0.0)}
    camera = {k: add(mul(v, scale), move) for k, v in cam.items()}
    camera["vfov_deg"] = 2.0 * math.degrees(math.atan(12.5 / 35.0))
    materials = {
        "white": diffuse(WHITE),
        "red": diffuse(RED),
        "green": diffuse(GREEN),
        "light": emissive((0.78, 0.78, 0.78), (17.0, 12.0, 4.0)),
    }
    notes = ["every vertex and the camera: cornell's x 1000 + (10000, -20000, 30000); "
             "radiance does not depend on scale or position, so the exact image is cornell's"]
    desc = "the Cornell box (scenes/cornell) scaled x1000 and moved to (1e4, -2e4, 3e4), camera too."
    emit("faraway", desc, parts, materials, camera, (), notes, digits=9)


# ---------------------------------------------------------------------------------------------
# column


def column():
    # The atrium's fluted column alone in a closed grey room, lit by a point light high on one
    # side; the camera faces the side that light meets at grazing angles, so that the light
    # changes from facet to facet across the flutes (concave grooves, convex ridges) at the
    # scale of a gather disc.
    room = Part("room", "grey")
    box(room, (-1.5, 0.0, -1.5), (1.5, 3.0, 1.5))
    room.tris = [(a, c, b) for (a, b, c) in room.tris]  # facing in
    shaft = Part("column", "column")
    fluted_column(shaft, 0.0, 0.0, 0.22, 0.0, 3.0)
    materials = {"grey": diffuse((0.5, 0.5, 0.5)), "column": diffuse((0.72, 0.62, 0.46))}
    camera = {"eye": (0.0, 1.5, -1.4), "target": (0.0, 1.5, 0.0), "vfov_deg": 40.0}
    lights = [{"type": "point", "position": (1.3, 2.8, 0.2), "intensity": (10.0, 10.0, 10.0)}]
    notes = [
        "room: the box [-1.5, 1.5] x [0, 3] x [-1.5, 1.5], facing in; column: the atrium's "
        "(48 sides, 16 flutes, r 0.22 m), floor to ceiling at the origin",
        "the column's face seen spans pixels x 80..183 of 256 (every row): photonmap compare --region 80,0,183,256",
    ]
    desc = ("a fluted column in a closed grey room, a point light high to one side; the camera "
            "faces the column where the light grazes it: light that changes flute by flute.")
    emit("column", desc, [room, shaft], materials, camera, lights, notes)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bunny", type=Path, default=DEFAULT_BUNNY, help="the Stanford bunny OBJ")
    ap.add_argument("names", nargs="*", help="scenes to make (default: all)")
    args = ap.parse_args()
    makers = {
        "sunroom": sunroom,
        "doorway": doorway,
        "bunny": lambda: bunny(args.bunny),
        "glassknot": glassknot,
        "faraway": faraway,
        "atrium": atrium,
        "column": column,
        "glossyroom": glossyroom,
        "pbrroom": pbrroom,
    }
    for name in args.names or makers:
        if name not in makers:
            sys.exit(f"unknown scene {name}; known: {', '.join(makers)}")
        makers[name]()


if __name__ == "__main__":
    main()
