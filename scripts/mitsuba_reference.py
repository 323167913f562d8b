#!/usr/bin/env python3
"""Independent reference images of our scenes, rendered with Mitsuba 3's path tracer.

    /work/mitsuba-venv/bin/python scripts/mitsuba_reference.py SCENE.toml OUTDIR
        (--minutes M | --spp N) [--threads T] [--variant llvm_ad_rgb] [--batch-spp B]
        [--small-dir tests/data/refs] [--compare OURS.exr] [--seed S]

Reads OUR scene file (TOML + OBJ + MTL, scenes/SCENES.md conventions) and builds the Mitsuba
scene itself: the OBJ is parsed here (Mitsuba's OBJ loader ignores `usemtl`) as
src/scene/obj.rs parses it (one vertex per distinct v/vt/vn corner, a triangle with normals
wound to their side), faces are grouped by material and each group becomes one `mi.Mesh`, with
vertex normals and texture coordinates when its triangles have them (all or none; flat
triangles are shaded with the face normal n = (v1 - v0) x (v2 - v0), as we do). Mapping (exact,
or refused):

    diffuse   -> twosided(diffuse kd)
    mirror    -> conductor, material "none", specular_reflectance ks (1: reflectance exactly 1)
    glass     -> dielectric, int_ior = ior, ext_ior = 1.0
    emissive  -> area emitter, radiance ke (front side only) + twosided(diffuse kd)
    point     -> point, intensity (W/sr)
    distant   -> directional, direction = the way the light travels (as ours), irradiance (W/m^2)
    environment -> constant (radiance), or envmap of the image times radiance, to_world = the
                 rotation (Mitsuba's equirectangular mapping is ours)
    map_Kd / kd_texture -> bitmap reflectance, bilinear, repeat (8-bit sRGB-decoded; v flipped
                 to Mitsuba's top-down convention); other maps and map options are refused
    camera    -> perspective, fov_axis y, look_at, hdrfilm rgb float32, box rfilter;
                 with aperture_radius > 0: thinlens (aperture_radius, focus_distance: the same
                 names and meaning; focus_distance defaults to |target - eye| as ours)
    [[mesh]]  -> scale, rotate, translate or matrix applied to the vertices here as
                 src/scene/transform.rs does (T R_n .. R_1 S, or M), the winding reversed where
                 the determinant is negative
    glossy    -> our normalised Phong itself (src/material/glossy.rs: kd / pi + ks (ns + 2) /
                 (2 pi) cos^ns of the angle to the mirror direction, two-sided, the same
                 lobe sampling), written here as a Mitsuba BSDF plugin in Python: the reference
                 checks our light transport on glossy surfaces, not the choice of the lobe
    principled -> glTF's metallic-roughness BRDF as src/material/principled.rs draws it (GGX,
                 height-correlated Smith, Schlick's Fresnel on the base colour by the metallic
                 value over (1 - m) 0.96 of it diffusely), a Python plugin too, its lobe sampled
                 by Mitsuba's own GGX visible-normal sampler (mi.MicrofacetDistribution), not ours
    spot, anything else -> error (no approximation)

Transport: `path`, max_depth -1, rr_depth 5, hide_emitters false, independent sampler.

Renders independent batches (seeds seed, seed+1, ...) of B samples per pixel each, averages
them, and estimates the noise left in the mean from the batch-to-batch variance:
noise RMSE = sqrt(mean over pixels and channels of var_batches / n_batches). With --minutes
the batches go on while the next one is expected to end within the budget (B is picked from
two short timing renders so that the budget holds about 32 batches, or given with --batch-spp).

Writes OUTDIR/<name>.exr (float32 RGB, row 0 at the top), OUTDIR/<name>.png (sRGB preview,
clamped at 1), OUTDIR/<name>.txt (version, variant, spp, batches, time, noise, means) and, with
--small-dir, <small-dir>/<name>-64.exr: the image box-downsampled to 64x64 (each pixel the mean
of a 4x4 block). --compare OURS.exr prints the mean of OURS against the reference's, per channel.
"""

import argparse
import datetime
import hashlib
import math
import os
import platform
import sys
import time
import tomllib
from pathlib import Path

import numpy as np


SCENE_DIR = ["."]


class Refused(Exception):
    """Something in the scene that Mitsuba cannot be given exactly."""


# ---------------------------------------------------------------------------------------------
# Our scene file, read the way src/scene/ reads it


def parse_mtl(path):
    """{name: {kd, ks, ke, ns, ni, illum}} (fields absent from the file are absent)."""
    mats, cur = {}, None
    for lineno, raw in enumerate(path.read_text().splitlines(), 1):
        w = raw.split("#", 1)[0].split()
        if not w:
            continue
        key = w[0]
        if key == "newmtl":
            cur = mats.setdefault(" ".join(w[1:]), {})
        elif cur is None:
            continue
        elif key in ("Kd", "Ks", "Ke"):
            cur[key.lower()] = [float(x) for x in w[1:4]]
        elif key == "Ns":
            cur["ns"] = float(w[1])
        elif key == "Ni":
            cur["ni"] = float(w[1])
        elif key == "illum":
            cur["illum"] = int(w[1])
        elif key in ("Pr", "Pm"):
            cur[{"Pr": "roughness", "Pm": "metallic"}[key]] = float(w[1])
        elif key.lower() == "map_kd":
            if any(x.startswith("-") for x in w[1:]):
                raise Refused(f"{path}:{lineno}: map_Kd options are not reproduced here")
            cur["kd_texture"] = str(path.parent / " ".join(w[1:]))
        elif key.lower().startswith("map_") or key.lower() in ("bump", "norm", "disp", "decal", "refl"):
            raise Refused(f"{path}:{lineno}: {key} is not reproduced here")
    return mats


def parse_obj(path):
    """As src/scene/obj.rs reads an OBJ: vertices (n x 3 float64, one per distinct v/vt/vn
    corner), triangles (m x 3, fans), per triangle its material name (None without
    `usemtl`), the materials of its `mtllib`s, and per vertex its normal (n x 3, zero where a
    corner has none; None when no corner has one) and texture coordinates (n x 2 or None).
    A triangle whose three corners have normals is wound to face their side."""
    v, vt, vn = [], [], []
    faces, tri_mat, mtl = [], [], {}
    material = None
    for lineno, raw in enumerate(path.read_text().splitlines(), 1):
        w = raw.split()
        if not w or w[0].startswith("#"):
            continue
        key = w[0]
        if key == "v":
            if len(w) not in (4, 5):
                # (v x y z r g b: vertex colours, which multiply the base colour, are not reproduced)
                raise Refused(f"{path}:{lineno}: vertex with {len(w) - 1} numbers")
            v.append([float(x) for x in w[1:4]])
        elif key == "vt":
            vt.append([float(x) for x in w[1:3]])
        elif key == "vn":
            n = np.array([float(x) for x in w[1:4]])
            length = np.linalg.norm(n)
            vn.append(n / length if length > 0 else np.zeros(3))
        elif key == "f":
            corners = []
            for ref in w[1:]:
                parts = ref.split("/") + ["", ""]
                def index(text, count):
                    if text == "":
                        return -1
                    i = int(text)
                    return i - 1 if i > 0 else count + i
                corners.append((index(parts[0], len(v)), index(parts[1], len(vt)), index(parts[2], len(vn))))
            if len(corners) < 3 or not all(0 <= c[0] < len(v) for c in corners):
                raise Refused(f"{path}:{lineno}: bad face")
            for k in range(1, len(corners) - 1):  # fan: (0,1,2),(0,2,3),...
                faces.append((corners[0], corners[k], corners[k + 1]))
                tri_mat.append(material)
        elif key == "usemtl":
            material = raw.split(None, 1)[1].strip()
        elif key == "mtllib":
            for k, m in parse_mtl(path.parent / raw.split(None, 1)[1].strip()).items():
                mtl.setdefault(k, m)
        elif key in ("o", "g", "s", "l"):
            pass
        else:
            raise Refused(f"{path}:{lineno}: unknown OBJ statement {key!r}")
    has_uv = any(c[1] >= 0 for f in faces for c in f)
    has_n = any(c[2] >= 0 and np.any(vn[c[2]]) for f in faces for c in f)
    verts, normals, uvs, tris, ids = [], [], [], [], {}
    for f in faces:
        tri = []
        for c in f:
            key = (c[0], c[1] if has_uv else -1, c[2] if has_n else -1)
            if key not in ids:
                ids[key] = len(verts)
                verts.append(v[c[0]])
                normals.append(vn[c[2]] if key[2] >= 0 else np.zeros(3))
                uvs.append(vt[c[1]] if key[1] >= 0 else [0.0, 0.0])
            tri.append(ids[key])
        if has_n:
            ns = [normals[i] for i in tri]
            a, b, c2 = (np.array(verts[i]) for i in tri)
            if all(np.any(n) for n in ns) and np.dot(np.cross(b - a, c2 - a), sum(ns)) < 0:
                tri = [tri[0], tri[2], tri[1]]
        tris.append(tri)
    return (np.array(verts, dtype=np.float64).reshape(-1, 3), np.array(tris, dtype=np.int64).reshape(-1, 3),
            tri_mat, mtl, np.array(normals).reshape(-1, 3) if has_n else None,
            np.array(uvs, dtype=np.float64).reshape(-1, 2) if has_uv else None)


def mtl_kind(m):
    """src/scene/materials.rs mtl_kind: Ke -> emissive; illum 3/5 mirror; 4/6/7 glass; 2 with Pr
    principled (as written by scripts/make_scenes.py: no Blender export here); 2 with Ks, Ns
    glossy."""
    if any(x > 0 for x in m.get("ke", [0, 0, 0])):
        return "emissive"
    illum = m.get("illum")
    if illum in (3, 5):
        return "mirror"
    if illum in (4, 6, 7):
        return "glass"
    if illum == 2 and "roughness" in m:
        return "principled"
    if illum == 2 and any(x > 0 for x in m.get("ks", [0, 0, 0])) and "ns" in m:
        return "glossy"
    return "diffuse"


def resolve_material(name, mtl, entry):
    """src/scene/mod.rs material(): the scene file's [materials.NAME] wins field by field."""
    if name is None:
        return {"type": "diffuse", "kd": [0.8, 0.8, 0.8]}
    if mtl is None and entry is None:
        raise Refused(f"material {name}: defined neither in the MTL nor in the scene file")
    mtl, entry = mtl or {}, entry or {}
    pick = lambda f, default: entry.get(f, mtl.get(f, default))  # noqa: E731
    kind = entry.get("type") or mtl_kind(mtl)
    m = {"type": kind}
    if kind in ("diffuse", "emissive", "glossy", "principled"):
        m["kd"] = pick("kd", [0.0, 0.0, 0.0])
        if "kd_texture" in entry:
            m["kd_texture"] = str(Path(SCENE_DIR[0]) / entry["kd_texture"])
        elif "kd_texture" in mtl:
            m["kd_texture"] = mtl["kd_texture"]
    if kind == "emissive":
        m["ke"] = pick("ke", [0.0, 0.0, 0.0])
    if kind == "mirror":
        m["ks"] = pick("ks", [1.0, 1.0, 1.0])
    if kind == "glass":
        m["ior"] = entry.get("ior", mtl.get("ni", 1.5))
    if kind == "glossy":
        m["ks"] = pick("ks", [0.0, 0.0, 0.0])
        m["ns"] = float(pick("ns", 1.0))
        if "kd_texture" in m or "ks_texture" in entry or "ks_texture" in mtl:
            raise Refused(f"material {name}: textured glossy materials are not drawn here")
    if kind == "principled":
        m["metallic"] = float(pick("metallic", 0.0))
        m["roughness"] = float(pick("roughness", 0.5))
        if "kd_texture" in m:
            raise Refused(f"material {name}: textured principled materials are not drawn here")
    if kind not in ("diffuse", "emissive", "mirror", "glass", "glossy", "principled"):
        raise Refused(f"material {name}: unknown type {kind!r}")
    return m


def rotation_matrix(axis, degrees):
    """Right-handed rotation about the axis through the origin (Rodrigues), as glam's."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    a = math.radians(float(degrees))
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return math.cos(a) * np.eye(3) + math.sin(a) * cross + (1 - math.cos(a)) * np.outer(k, k)


def mesh_transform(i, mesh):
    """(linear 3x3, translation) of a [[mesh]] entry: `matrix` (12 or 16 numbers, row-major),
    or scale, then the rotations in order, then translate (src/scene/transform.rs)."""
    if "matrix" in mesh:
        m = np.array(mesh["matrix"], dtype=np.float64)
        if any(k in mesh for k in ("scale", "rotate", "translate")) or len(m) not in (12, 16):
            raise Refused(f"mesh[{i}].matrix: 12 or 16 numbers, and not with scale/rotate/translate")
        if len(m) == 16 and list(m[12:]) != [0.0, 0.0, 0.0, 1.0]:
            raise Refused(f"mesh[{i}].matrix: not affine")
        m = m[:12].reshape(3, 4)
        return m[:, :3], m[:, 3]
    scale = mesh.get("scale", 1.0)
    scale = np.array([scale] * 3 if isinstance(scale, (int, float)) else scale, dtype=np.float64)
    linear = np.diag(scale)
    rotate = mesh.get("rotate", [])
    for r in [rotate] if isinstance(rotate, dict) else rotate:
        linear = rotation_matrix(r["axis"], r["degrees"]) @ linear
    return linear, np.array(mesh.get("translate", [0.0, 0.0, 0.0]), dtype=np.float64)


def load_scene(toml_path):
    """Camera, {material name: (material, vertices, triangles)}, lights, as our loader sees them."""
    toml_path = Path(toml_path)
    SCENE_DIR[0] = str(toml_path.parent)
    scene = tomllib.loads(toml_path.read_text())
    # [[portal]] only changes where our photons are sent, not the light: nothing to give Mitsuba.
    unknown = set(scene) - {"camera", "mesh", "materials", "light", "render", "portal"}
    if unknown:
        raise Refused(f"{toml_path}: unknown tables {sorted(unknown)}")
    entries = scene.get("materials", {})
    groups, mtl_all = {}, {}
    for i, mesh in enumerate(scene.get("mesh", [])):
        unknown = set(mesh) - {"obj", "material", "scale", "rotate", "translate", "matrix"}
        if unknown:
            raise Refused(f"mesh[{i}]: unknown keys {sorted(unknown)}")
        verts, tris, tri_mat, mtl, normals, uvs = parse_obj(toml_path.parent / mesh["obj"])
        linear, translate = mesh_transform(i, mesh)
        verts = verts @ linear.T + translate
        if normals is not None:  # by the inverse transpose, zeros kept
            normals = normals @ np.linalg.inv(linear)
            length = np.linalg.norm(normals, axis=1, keepdims=True)
            normals = np.where(length > 0, normals / np.where(length > 0, length, 1), 0.0)
        if np.linalg.det(linear) < 0:  # a mirroring transform flips the winding; the renderer restores it
            tris = tris[:, [0, 2, 1]]
        if "material" in mesh:
            tri_mat = [mesh["material"]] * len(tris)
        for k, v in mtl.items():
            mtl_all.setdefault(k, v)
        names = np.array([m if m is not None else "\0default" for m in tri_mat], dtype=object)
        for name in dict.fromkeys(names):
            sel = tris[names == name]
            used = np.unique(sel)
            remap = np.full(len(verts), -1, dtype=np.int64)
            remap[used] = np.arange(len(used))
            groups.setdefault(name, []).append((verts[used], remap[sel],
                                                None if normals is None else normals[used],
                                                None if uvs is None else uvs[used]))
    out = {}
    for name, pieces in groups.items():
        real = None if name == "\0default" else name
        material = resolve_material(real, mtl_all.get(real), entries.get(real))
        vs, ts, ns, us, base = [], [], [], [], 0
        for v, t, n, u in pieces:
            vs.append(v)
            ts.append(t + base)
            ns.append(n)
            us.append(u)
            base += len(v)
        def joined(parts, width, what):
            if all(p is None for p in parts):
                return None
            if any(p is None for p in parts) or (what == "normals" and not np.all(np.any(np.concatenate(parts), axis=1))):
                raise Refused(f"material {name}: some of its triangles have vertex {what} and some not")
            return np.concatenate(parts).reshape(-1, width)
        out[real or "(default grey)"] = (material, np.concatenate(vs), np.concatenate(ts),
                                         joined(ns, 3, "normals"), joined(us, 2, "texture coordinates"))
    lights = scene.get("light", [])
    for light in lights:
        if light.get("type") not in ("point", "distant", "environment"):
            raise Refused(f"light type {light.get('type')!r}: only point, distant and environment map exactly")
    return scene["camera"], out, lights


# ---------------------------------------------------------------------------------------------
# The Mitsuba scene


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def bsdf_dict(m):
    if m["type"] in ("diffuse", "emissive"):
        reflectance = rgb(m["kd"])
        if "kd_texture" in m:
            # 8-bit images are sRGB-decoded (raw false), EXR/HDR linear; bilinear, repeat: as ours.
            reflectance = {"type": "bitmap", "filename": m["kd_texture"], "filter_type": "bilinear",
                           "wrap_mode": "repeat"}
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": reflectance}}
    if m["type"] == "mirror":
        return {"type": "conductor", "material": "none", "specular_reflectance": rgb(m["ks"])}
    if m["type"] == "glass":
        return {"type": "dielectric", "int_ior": float(m["ior"]), "ext_ior": 1.0}
    if m["type"] == "glossy":
        d = {"type": "ours_phong", "ns": float(m["ns"])}
        for key in ("kd", "ks"):
            for c, v in zip("rgb", m[key]):
                d[f"{key}_{c}"] = float(v)
        return d
    if m["type"] == "principled":
        # src/material/principled.rs: alpha = roughness^2, at least MIN_ALPHA.
        d = {"type": "ours_principled", "metallic": m["metallic"], "alpha": max(m["roughness"] ** 2, 0.01)}
        for c, v in zip("rgb", m["kd"]):
            d[f"base_{c}"] = min(max(float(v), 0.0), 1.0)
        return d
    raise Refused(m["type"])


def two_sided_mixture(mi, dr):
    """The base class of our BSDF plugins: a glossy lobe and a Lambertian part, two-sided (both
    directions mirrored to the side the viewer is on, as ours flips the normal). A subclass
    gives `f_pdf(wi, wo)` (f and the mixture's density for local directions on the upper side,
    wi toward the viewer, wo toward the light) and `draw(wi, sample1, sample2)` (whether the
    lobe was picked, and the direction); `eval` is f cos, `pdf` the mixture's, as ours."""
    glossy = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
    diffuse = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide

    class TwoSidedMixture(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_components = [glossy, diffuse]
            self.m_flags = glossy | diffuse

        def side(self, si):
            return dr.select(mi.Frame3f.cos_theta(si.wi) < 0, -1.0, 1.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            s = self.side(si)
            wi, wo = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * s), mi.Vector3f(wo.x, wo.y, wo.z * s)
            f, pdf, valid = self.f_pdf(wi, wo)
            ok = active & valid
            return dr.select(ok, f * wo.z, 0.0), dr.select(ok, pdf, 0.0)

        def eval(self, ctx, si, wo, active=True):
            return self.eval_pdf(ctx, si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            return self.eval_pdf(ctx, si, wo, active)[1]

        def sample(self, ctx, si, sample1, sample2, active=True):
            s = self.side(si)
            wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * s)
            lobe, wo = self.draw(wi, sample1, sample2)
            f, pdf, valid = self.f_pdf(wi, wo)
            bs = mi.BSDFSample3f()
            bs.wo = mi.Vector3f(wo.x, wo.y, wo.z * s)
            bs.pdf = pdf
            bs.eta = 1.0
            bs.sampled_type = dr.select(lobe, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                        mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
            bs.sampled_component = dr.select(lobe, mi.UInt32(0), mi.UInt32(1))
            ok = active & valid & (pdf > 0)
            return bs, dr.select(ok, f * wo.z / pdf, 0.0)

        def traverse(self, callback):
            pass

    return TwoSidedMixture


def register_phong(mi, dr):
    """Registers `ours_phong`: src/material/glossy.rs's normalised Phong (Lafortune & Willems
    1994) as a Mitsuba BSDF, the lobe picked with probability mean(ks) / (mean(kd) + mean(ks))
    and sampled around the mirror direction with density (ns + 1) / (2 pi) cos^ns, samples
    below the surface rejected, as ours."""

    class OursPhong(two_sided_mixture(mi, dr)):
        def __init__(self, props):
            super().__init__(props)
            kd = [max(props[f"kd_{c}"], 0.0) for c in "rgb"]
            ks = [max(props[f"ks_{c}"], 0.0) for c in "rgb"]
            self.kd, self.ks, self.ns = mi.Color3f(*kd), mi.Color3f(*ks), float(props["ns"])
            self.ps = sum(ks) / (sum(kd) + sum(ks)) if sum(kd) + sum(ks) > 0 else 0.0

        def f_pdf(self, wi, wo):
            mirror = mi.Vector3f(-wi.x, -wi.y, wi.z)
            lobe = dr.power(dr.maximum(dr.dot(mirror, wo), 0.0), self.ns)
            f = self.kd * dr.inv_pi + self.ks * ((self.ns + 2.0) * 0.5 * dr.inv_pi * lobe)
            pdf = (1.0 - self.ps) * wo.z * dr.inv_pi + self.ps * (self.ns + 1.0) * 0.5 * dr.inv_pi * lobe
            valid = (wi.z > 0) & (wo.z > 0)
            return f, dr.select(valid, pdf, 0.0), valid

        def draw(self, wi, sample1, sample2):
            lobe = sample1 < self.ps
            cos_a = dr.power(sample2.x, 1.0 / (self.ns + 1.0))
            sin_a = dr.safe_sqrt(1.0 - cos_a * cos_a)
            sp, cp = dr.sincos(dr.two_pi * sample2.y)
            around = mi.Frame3f(mi.Vector3f(-wi.x, -wi.y, wi.z)).to_world(mi.Vector3f(sin_a * cp, sin_a * sp, cos_a))
            return lobe, dr.select(lobe, around, mi.warp.square_to_cosine_hemisphere(sample2))

        def to_string(self):
            return f"OursPhong[ns={self.ns}, ps={self.ps}]"

    mi.register_bsdf("ours_phong", lambda props: OursPhong(props))


def register_principled(mi, dr):
    """Registers `ours_principled`: src/material/principled.rs's BRDF: f = kd / pi + F(wi . h)
    D(h) V, kd = (1 - m) 0.96 base, F Schlick's with F0 = (1 - m) 0.04 + m base rising by m (1 -
    base) (1 - c)^5, D GGX, V glTF's height-correlated Smith term. The lobe is picked with
    probability s / (s + d) (s the mean of F at the viewer's cosine, d the mean of kd) and
    sampled by Mitsuba's GGX visible-normal sampler, not ours."""

    class OursPrincipled(two_sided_mixture(mi, dr)):
        def __init__(self, props):
            super().__init__(props)
            base = [props[f"base_{c}"] for c in "rgb"]
            m, self.alpha = float(props["metallic"]), float(props["alpha"])
            self.kd = mi.Color3f(*[(1.0 - m) * 0.96 * b for b in base])
            self.f0 = mi.Color3f(*[(1.0 - m) * 0.04 + m * b for b in base])
            self.rise = mi.Color3f(*[m * (1.0 - b) for b in base])
            self.kd_sum = sum((1.0 - m) * 0.96 * b for b in base)
            self.distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)

        def fresnel(self, c):
            x = dr.clip(1.0 - c, 0.0, 1.0)
            return self.f0 + self.rise * (x * x * x * x * x)

        def lobe_probability(self, wi):
            f = self.fresnel(wi.z)
            s = f[0] + f[1] + f[2]
            return dr.select(s + self.kd_sum > 0, s / (s + self.kd_sum), 0.0)

        def f_pdf(self, wi, wo):
            h = dr.normalize(wi + wo)
            a2 = self.alpha * self.alpha
            root = lambda c: dr.sqrt(c * c * (1.0 - a2) + a2)  # noqa: E731
            v = 0.5 / (wo.z * root(wi.z) + wi.z * root(wo.z))
            f = self.kd * dr.inv_pi + self.fresnel(dr.dot(wi, h)) * (self.distr.eval(h) * v)
            ps = self.lobe_probability(wi)
            lobe = self.distr.pdf(wi, h) / (4.0 * dr.dot(wo, h))
            pdf = (1.0 - ps) * wo.z * dr.inv_pi + ps * lobe
            valid = (wi.z > 0) & (wo.z > 0)
            return f, dr.select(valid, pdf, 0.0), valid

        def draw(self, wi, sample1, sample2):
            lobe = sample1 < self.lobe_probability(wi)
            normal, _ = self.distr.sample(wi, sample2)
            return lobe, dr.select(lobe, mi.reflect(wi, normal), mi.warp.square_to_cosine_hemisphere(sample2))

        def to_string(self):
            return f"OursPrincipled[alpha={self.alpha}]"

    mi.register_bsdf("ours_principled", lambda props: OursPrincipled(props))


def sensor_dict(mi, camera, eye, target, up, spp):
    """The sensor of our camera entry (its fov, lens and film) looking from eye at target:
    `perspective`, or `thinlens` with the same aperture_radius and focus_distance."""
    if "key" in camera and any(k in key for key in camera["key"] for k in ("aperture_radius", "focus_distance")):
        raise Refused("keyed lenses are not reproduced here")
    aperture = float(camera.get("aperture_radius", 0.0))
    lens = {}
    if aperture > 0:
        focus = camera.get("focus_distance")
        focus = np.linalg.norm(np.asarray(target, dtype=np.float64) - np.asarray(eye, dtype=np.float64)) \
            if focus is None else focus
        lens = {"type": "thinlens", "aperture_radius": aperture, "focus_distance": float(focus)}
    return {
        "type": "perspective",
        "fov_axis": "y",
        "fov": float(camera["vfov_deg"]),
        "to_world": mi.ScalarTransform4f.look_at(
            origin=[float(x) for x in eye], target=[float(x) for x in target], up=[float(x) for x in up]
        ),
        "film": {
            "type": "hdrfilm",
            "width": int(camera["width"]),
            "height": int(camera["height"]),
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
            "component_format": "float32",
        },
        "sampler": {"type": "independent", "sample_count": spp},
    } | lens


def build(mi, camera, groups, lights, spp):
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1, "rr_depth": 5, "hide_emitters": False},
        "sensor": sensor_dict(mi, camera, camera["eye"], camera["target"], camera["up"], spp),
    }
    for k, (name, (m, v, t, n, uv)) in enumerate(groups.items()):
        props = mi.Properties()
        props["bsdf"] = mi.load_dict(bsdf_dict(m))
        if m["type"] == "emissive" and max(m["ke"]) > 0:
            props["emitter"] = mi.load_dict({"type": "area", "radiance": rgb(m["ke"])})
        mesh = mi.Mesh(f"m{k}_{name}", len(v), len(t), props, has_vertex_normals=n is not None,
                       has_vertex_texcoords=uv is not None)
        params = mi.traverse(mesh)
        params["vertex_positions"] = type(params["vertex_positions"])(v.astype(np.float32).ravel())
        params["faces"] = type(params["faces"])(t.astype(np.uint32).ravel())
        if n is not None:
            params["vertex_normals"] = type(params["vertex_normals"])(n.astype(np.float32).ravel())
        if uv is not None:
            # Ours have v up (v = 0 the image's bottom row); Mitsuba's bitmaps have v = 0 at the top.
            flipped = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1)
            params["vertex_texcoords"] = type(params["vertex_texcoords"])(flipped.astype(np.float32).ravel())
        params.update()
        scene[f"mesh{k}"] = mesh
    for k, light in enumerate(lights):
        if light["type"] == "point":
            scene[f"light{k}"] = {"type": "point", "position": [float(x) for x in light["position"]],
                                  "intensity": rgb(light["intensity"])}
        elif light["type"] == "distant":
            d = np.array(light["direction"], dtype=np.float64)
            d /= np.linalg.norm(d)
            # Mitsuba's `direction` is the way the light propagates, as ours (src/light/distant.rs).
            scene[f"light{k}"] = {"type": "directional", "direction": [float(x) for x in d],
                                  "irradiance": rgb(light["irradiance"])}
        elif light["type"] == "environment":
            radiance = [float(x) for x in light.get("radiance", [1.0, 1.0, 1.0])]
            rotate = light.get("rotate", [])
            linear = np.eye(3)
            for r in [rotate] if isinstance(rotate, dict) else rotate:
                linear = rotation_matrix(r["axis"], r["degrees"]) @ linear
            to_world = np.eye(4)
            to_world[:3, :3] = linear
            if "map" not in light:
                scene[f"light{k}"] = {"type": "constant", "radiance": rgb(radiance)}
            else:
                # Mitsuba's envmap mapping is the one src/light/environment.rs follows; a colour
                # factor is multiplied into a copy of the image.
                bitmap = np.array(mi.Bitmap(str(SCENE_DIR[0] + "/" + light["map"])).convert(
                    mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False), dtype=np.float32)
                bitmap = bitmap * np.array(radiance, dtype=np.float32)
                scene[f"light{k}"] = {"type": "envmap", "bitmap": mi.Bitmap(bitmap),
                                      "to_world": mi.ScalarTransform4f(to_world.tolist())}
    return mi.load_dict(scene)


# ---------------------------------------------------------------------------------------------
# Rendering in batches


def render_batches(mi, scene, args, log):
    def one(spp, seed):
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[:, :, :3]
        return img, time.perf_counter() - t0

    budget = None if args.minutes is None else args.minutes * 60.0
    batch_spp = args.batch_spp
    seed = args.seed
    start = time.perf_counter()
    if batch_spp is None:
        if budget is None:
            batch_spp = 32
        else:
            # Two short timing renders (the first includes compiling the kernels), not kept.
            probe = 4
            _, t_first = one(probe, 10_000_000 + seed)
            _, t_probe = one(probe, 10_000_001 + seed)
            per_spp = t_probe / probe
            left = budget - (time.perf_counter() - start)
            batch_spp = int(max(4, min(args.max_batch_spp, left / 32 / per_spp)))
            log(f"timing: first {probe}-spp render {t_first:.2f} s, second {t_probe:.2f} s "
                f"-> {batch_spp} spp a batch")
    n_target = None if args.spp is None else max(2, math.ceil(args.spp / batch_spp))
    total = None
    sq = None
    times = []
    n = 0
    while True:
        if n_target is not None and n >= n_target:
            break
        if budget is not None and n >= 2:
            elapsed = time.perf_counter() - start
            if elapsed + np.mean(times[1:] or times) > budget:
                break
        img, dt = one(batch_spp, seed + n)
        if not np.all(np.isfinite(img)):
            bad = int(np.sum(~np.isfinite(img)))
            raise RuntimeError(f"batch {n}: {bad} non-finite values")
        total = img if total is None else total + img
        sq = img * img if sq is None else sq + img * img
        times.append(dt)
        n += 1
        if n == 1 or n % 8 == 0:
            log(f"batch {n}: {dt:.2f} s, running mean {total.mean() / n:.5f}")
    mean = total / n
    var = np.maximum(sq / n - mean * mean, 0.0) * n / (n - 1)  # unbiased, batch to batch
    noise = math.sqrt(var.mean() / n)
    return mean.astype(np.float32), noise, n, batch_spp, time.perf_counter() - start


def write_exr(mi, path, img):
    mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32), mi.Bitmap.PixelFormat.RGB).write(str(path))


def write_png(mi, path, img):
    b = mi.Bitmap(np.ascontiguousarray(np.clip(img, 0.0, 1.0), dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
    b.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(str(path))


def downsample(img, factor):
    h, w, c = img.shape
    return img.reshape(h // factor, factor, w // factor, factor, c).astype(np.float64).mean(axis=(1, 3))


def read_exr(mi, path):
    return np.array(mi.Bitmap(str(path)), dtype=np.float64)[:, :, :3]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", type=Path, help="our scene file (TOML)")
    ap.add_argument("outdir", type=Path, help="where <name>.exr, .png and .txt go")
    budget = ap.add_mutually_exclusive_group(required=True)
    budget.add_argument("--minutes", type=float, help="wall-time budget")
    budget.add_argument("--spp", type=int, help="total samples per pixel")
    ap.add_argument("--threads", type=int, default=2, help="Dr.Jit worker threads (default 2)")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (llvm_ad_rgb or scalar_rgb)")
    ap.add_argument("--batch-spp", type=int, help="samples per pixel in each batch (default: from timing)")
    ap.add_argument("--max-batch-spp", type=int, default=128, help="cap on the automatic batch size (memory)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the first batch (the others follow)")
    ap.add_argument("--name", help="output name (default: the scene file's stem)")
    ap.add_argument("--small-dir", type=Path, help="also write <small-dir>/<name>-64.exr (4x4 box-downsampled)")
    ap.add_argument("--compare", type=Path, help="print the mean of this EXR (ours) against the reference's")
    args = ap.parse_args()
    name = args.name or args.scene.stem

    def log(msg):
        print(f"[{name}] {msg}", file=sys.stderr, flush=True)

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    register_phong(mi, dr)
    register_principled(mi, dr)
    if args.variant.startswith("llvm"):
        dr.set_thread_count(args.threads)
    try:
        camera, groups, lights = load_scene(args.scene)
    except Refused as e:
        sys.exit(f"{args.scene}: refused: {e}")
    for mname, (m, v, t, _n, _uv) in groups.items():
        log(f"material {mname}: {m['type']}, {len(t)} triangles")
    t0 = time.perf_counter()
    scene = build(mi, camera, groups, lights, 4)
    log(f"scene built in {time.perf_counter() - t0:.2f} s; rendering ({args.variant}, {args.threads} threads)")
    img, noise, n, batch_spp, wall = render_batches(mi, scene, args, log)
    h, w = img.shape[:2]
    means = img.reshape(-1, 3).mean(axis=0)

    args.outdir.mkdir(parents=True, exist_ok=True)
    write_exr(mi, args.outdir / f"{name}.exr", img)
    write_png(mi, args.outdir / f"{name}.png", img)
    if args.small_dir is not None:
        if h % 4 or w % 4:
            sys.exit(f"{w}x{h} is not divisible by 4")
        args.small_dir.mkdir(parents=True, exist_ok=True)
        write_exr(mi, args.small_dir / f"{name}-64.exr", downsample(img, 4).astype(np.float32))
    digest = hashlib.sha256()
    digest.update(args.scene.read_bytes())
    report = [
        f"reference: {name} ({args.scene}, sha256 of the TOML {digest.hexdigest()[:16]})",
        f"renderer: Mitsuba {mi.__version__}, variant {args.variant}, integrator path (max_depth -1, "
        "rr_depth 5, hide_emitters false), independent sampler, box filter",
        f"size: {w}x{h}",
        f"spp: {n * batch_spp} total = {n} batches x {batch_spp} spp (seeds {args.seed}..{args.seed + n - 1})",
        f"wall time: {wall:.1f} s on {args.threads} threads ({platform.node()}, {os.cpu_count()} cores)",
        f"noise RMSE (estimated from batch-to-batch variance): {noise:.6f}",
        f"mean: R {means[0]:.6f} G {means[1]:.6f} B {means[2]:.6f} (all {means.mean():.6f})",
        f"date: {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
        "command: " + " ".join([Path(sys.executable).as_posix(), *sys.argv]),
    ]
    (args.outdir / f"{name}.txt").write_text("\n".join(report) + "\n")
    print("\n".join(report))
    if args.compare is not None:
        ours = read_exr(mi, args.compare).reshape(-1, 3).mean(axis=0)
        rel = ours / means - 1.0
        print(f"compare: ours {args.compare} mean R {ours[0]:.6f} G {ours[1]:.6f} B {ours[2]:.6f}; "
              f"ours/reference - 1: R {rel[0]:+.2%} G {rel[1]:+.2%} B {rel[2]:+.2%} "
              f"(all {ours.mean() / means.mean() - 1:+.2%})")


if __name__ == "__main__":
    main()
