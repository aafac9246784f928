#!/usr/bin/env python3
"""Convert a vdbmarch scene JSON (docs/scene-format.md) into a pbrt-v4 scene file.

    vdbmarch_to_pbrt.py SCENE.json OUT.pbrt [--image out.exr] [--resolution W H] [--spp N]
                        [--max-depth N] [--seed N] [--nanovdb-convert PATH] [--nvdb-dir DIR]

VDB media are converted to .nvdb (NanoVDB 32.3, the version pbrt-v4 reads) with nanovdb_convert
(default /tmp/pbrt-v4-build/nanovdb_convert), and a lat-long environment map to pbrt's equal-area
square map with pbrt's `imgtool makeequiarea`, next to OUT.pbrt unless --nvdb-dir says otherwise.
Anything the converter cannot map faithfully exits with status 1 and a message naming the key
(docs/pbrt-peer.md lists the mapping). Warnings go to stderr.

Mapping summary (pbrt-v4 normalises every light spectrum by the photometric Y of its illuminant,
so an "rgb L/I" of [1 1 1] is radiance/intensity 1 in the output's linear sRGB units):
  camera      Scale -1 1 1 + LookAt (pbrt is left-handed: without the mirror the image is flipped
              left-right); "fov" spans the shorter image axis, vdbmarch's fov_deg is vertical.
  point       "point" rgb I = intensity
  spot        "spot" rgb I = intensity, coneangle = cone_deg, conedeltaangle = falloff_deg (both
              renderers use a smoothstep in the cosine over the same band)
  directional "distant" to = direction, rgb L = irradiance
  sphere      sphere shape with a "diffuse" area light, rgb L = power / (4 pi^2 r^2), black material
  background  "infinite" rgb L = background
  environment imgtool makeequiarea, "infinite" filename, scale; light transform Rotate(rotation, y)
              times the axis change from vdbmarch's lat-long (+y up, u=0 along -z) to pbrt's (+z up)
  homogeneous MakeNamedMedium "homogeneous" (sigma_a, sigma_s, g as given, RGB uplifted to spectra)
  vdb         MakeNamedMedium "nanovdb" under the medium's transform, "scale" = density_scale
  media       world media with bounds (or a vdb grid's bounding box) get an enclosing box with
              Material "interface" and MediumInterface NAME ""; surfaces get MediumInterface
              interior exterior, exterior = the world medium whose bounds hold the surface
  surfaces    box/mesh -> world-space trianglemesh oriented outwards, sphere -> "sphere" under the
              transform (p' = T R S p), diffuse -> "diffuse" reflectance, dielectric -> eta, interface
  render      spp -> zsobol pixelsamples, max_depth -> volpath maxdepth, box pixel filter; upstream
              pbrt counts glass bounces in maxdepth, vdbmarch does not: --specular-depth N with the
              patched pbrt (patches/volpath_maxspeculardepth.patch) counts them apart, as vdbmarch
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys

ERR_PREFIX = "vdbmarch_to_pbrt: error: "


def die(msg):
    sys.stderr.write(ERR_PREFIX + msg + "\n")
    sys.exit(1)


def warn(msg):
    sys.stderr.write("vdbmarch_to_pbrt: warning: " + msg + "\n")


# ---------------------------------------------------------------- small vector helpers
def sub(a, b): return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
def add(a, b): return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def norm(a): return math.sqrt(dot(a, a))


def matmul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def xform_point(M, p):
    return [M[i][0] * p[0] + M[i][1] * p[1] + M[i][2] * p[2] + M[i][3] for i in range(3)]


def det3(M):
    return (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1])
            - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
            + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]))


def inverse_affine(M):
    a = [r[:3] for r in M[:3]]
    d = det3(M)
    if abs(d) < 1e-300:
        return None
    inv = [[0.0] * 3 for _ in range(3)]
    for i in range(3):
        for j in range(3):
            r = [x for x in range(3) if x != j]
            c = [x for x in range(3) if x != i]
            minor = a[r[0]][c[0]] * a[r[1]][c[1]] - a[r[0]][c[1]] * a[r[1]][c[0]]
            inv[i][j] = (-1) ** (i + j) * minor / d
    t = [M[0][3], M[1][3], M[2][3]]
    it = [-sum(inv[i][k] * t[k] for k in range(3)) for i in range(3)]
    return [inv[0] + [it[0]], inv[1] + [it[1]], inv[2] + [it[2]], [0, 0, 0, 1]]


IDENT = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]


# ---------------------------------------------------------------- key checking
def check_keys(obj, allowed, path):
    if not isinstance(obj, dict):
        die("%s: expected an object" % path)
    for k in obj:
        if k not in allowed:
            die("%s.%s: not supported by the pbrt converter (supported here: %s)"
                % (path, k, ", ".join(sorted(allowed))))


def colour(v, path, default):
    if v is None:
        v = default
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return [float(v)] * 3
    if isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) for x in v):
        return [float(x) for x in v]
    die("%s: expected a colour (number or [r, g, b]), got %r" % (path, v))


def vec3(v, path, default=None):
    if v is None:
        if default is None:
            die("%s: required" % path)
        v = default
    if isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) for x in v):
        return [float(x) for x in v]
    die("%s: expected [x, y, z], got %r" % (path, v))


def num(v, path, default):
    if v is None:
        return default
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return float(v)
    die("%s: expected a number, got %r" % (path, v))


def f(x):
    return "%.9g" % x


def fl(xs):
    return " ".join(f(x) for x in xs)


# ---------------------------------------------------------------- transforms
def transform_matrix(t, path):
    """vdbmarch transform object -> 4x4 row-major matrix acting on column vectors."""
    if t is None:
        return [r[:] for r in IDENT]
    check_keys(t, {"scale", "rotate", "translate", "matrix"}, path)
    if "matrix" in t:
        if len(t) != 1:
            die("%s.matrix: cannot be combined with scale/rotate/translate" % path)
        m = t["matrix"]
        if not (isinstance(m, list) and len(m) == 16):
            die("%s.matrix: expected 16 numbers" % path)
        M = [[float(m[4 * i + j]) for j in range(4)] for i in range(4)]
        if M[3] != [0.0, 0.0, 0.0, 1.0]:
            die("%s.matrix: last row must be 0 0 0 1" % path)
        return M
    s = t.get("scale", 1)
    if isinstance(s, (int, float)):
        s = [s, s, s]
    s = vec3(s, path + ".scale")
    S = [[s[0], 0, 0, 0], [0, s[1], 0, 0], [0, 0, s[2], 0], [0, 0, 0, 1]]
    R = [r[:] for r in IDENT]
    if "rotate" in t:
        r = t["rotate"]
        if not (isinstance(r, list) and len(r) == 4):
            die("%s.rotate: expected [ax, ay, az, angle_deg]" % path)
        ax = [float(x) for x in r[:3]]
        n = norm(ax)
        if n == 0:
            die("%s.rotate: zero axis" % path)
        x, y, z = (a / n for a in ax)
        th = math.radians(float(r[3]))
        c, si = math.cos(th), math.sin(th)
        C = 1 - c
        R = [[c + x * x * C, x * y * C - z * si, x * z * C + y * si, 0],
             [y * x * C + z * si, c + y * y * C, y * z * C - x * si, 0],
             [z * x * C - y * si, z * y * C + x * si, c + z * z * C, 0],
             [0, 0, 0, 1]]
    tr = vec3(t.get("translate", [0, 0, 0]), path + ".translate")
    T = [[1, 0, 0, tr[0]], [0, 1, 0, tr[1]], [0, 0, 1, tr[2]], [0, 0, 0, 1]]
    return matmul(T, matmul(R, S))  # scale, then rotate, then translate


def pbrt_transform(M):
    """pbrt's Transform/ConcatTransform read the matrix transposed (column-major list)."""
    return "ConcatTransform [ %s ]" % fl([M[i][j] for j in range(4) for i in range(4)])


# ---------------------------------------------------------------- geometry
BOX_V = [[-0.5, -0.5, -0.5], [0.5, -0.5, -0.5], [0.5, 0.5, -0.5], [-0.5, 0.5, -0.5],
         [-0.5, -0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, 0.5], [-0.5, 0.5, 0.5]]
# counter-clockwise seen from outside (outward normals by the right-hand rule)
BOX_F = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
         [3, 7, 6], [3, 6, 2], [1, 2, 6], [1, 6, 5], [0, 4, 7], [0, 7, 3]]


def signed_volume(P, F):
    return sum(dot(P[a], cross(P[b], P[c])) for a, b, c in F) / 6.0


def box_mesh(lo, hi, M=None):
    P = [[lo[i] + (v[i] + 0.5) * (hi[i] - lo[i]) for i in range(3)] for v in BOX_V]
    if M is not None:
        P = [xform_point(M, p) for p in P]
    F = [tri[:] for tri in BOX_F]
    if signed_volume(P, F) < 0:
        F = [[a, c, b] for a, b, c in F]
    return P, F


def bbox_of(P):
    return [min(p[i] for p in P) for i in range(3)], [max(p[i] for p in P) for i in range(3)]


def read_obj(path, key):
    P, F = [], []
    try:
        fh = open(path)
    except OSError as e:
        die("%s: %s: %s" % (key, path, e))
    with fh:
        for line in fh:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                P.append([float(x) for x in w[1:4]])
            elif w[0] == "f":
                idx = []
                for tok in w[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(P) + i)
                for k in range(1, len(idx) - 1):
                    F.append([idx[0], idx[k], idx[k + 1]])
    if not F:
        die("%s: %s has no faces" % (key, path))
    return P, F


def is_closed(F):
    edges = {}
    for a, b, c in F:
        for u, v in ((a, b), (b, c), (c, a)):
            e = (min(u, v), max(u, v))
            edges[e] = edges.get(e, 0) + 1
    return all(n == 2 for n in edges.values())


def vertex_normals(P, F):
    N = [[0.0, 0.0, 0.0] for _ in P]
    for a, b, c in F:
        n = cross(sub(P[b], P[a]), sub(P[c], P[a]))  # length = 2 * area: area-weighted
        for i in (a, b, c):
            N[i] = add(N[i], n)
    return [[x / (norm(n) or 1.0) for x in n] for n in N]


def trianglemesh(P, F, N=None, indent="  "):
    s = indent + 'Shape "trianglemesh"\n'
    s += indent + '  "point3 P" [ %s ]\n' % fl([x for p in P for x in p])
    s += indent + '  "integer indices" [ %s ]\n' % " ".join(str(i) for t in F for i in t)
    if N is not None:
        s += indent + '  "normal N" [ %s ]\n' % fl([x for n in N for x in n])
    return s


# ---------------------------------------------------------------- nanovdb
def nvdb_grids(path):
    """Grid name -> (world bbox min, max, voxel size) from a .nvdb file's segment metadata."""
    out = {}
    with open(path, "rb") as fh:
        while True:
            hdr = fh.read(16)
            if len(hdr) < 16:
                break
            magic, version, count, codec = struct.unpack("<QIHH", hdr)
            metas = []
            for _ in range(count):
                m = fh.read(176)
                gridSize, fileSize, nameKey, voxelCount = struct.unpack_from("<QQQQ", m, 0)
                wb = struct.unpack_from("<6d", m, 40)
                vs = struct.unpack_from("<3d", m, 112)
                nameSize = struct.unpack_from("<I", m, 136)[0]
                name = fh.read(nameSize).rstrip(b"\0").decode()
                metas.append((name, fileSize, list(wb[:3]), list(wb[3:]), list(vs)))
            for name, fileSize, lo, hi, vs in metas:
                out[name] = (lo, hi, vs)
                fh.seek(fileSize, 1)
    return out


# ---------------------------------------------------------------- main conversion
def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--image", help="EXR written by pbrt (default: OUT with .exr)")
    ap.add_argument("--resolution", nargs=2, type=int, metavar=("W", "H"))
    ap.add_argument("--spp", type=int)
    ap.add_argument("--max-depth", type=int, help="pbrt maxdepth (default: render.max_depth)")
    ap.add_argument("--seed", type=int)
    ap.add_argument("--specular-depth", type=int, metavar="N",
                    help="needs pbrt with patches/volpath_maxspeculardepth.patch: glass bounces do not count "
                         "towards maxdepth (as in vdbmarch) and a path ends after N of them (vdbmarch's "
                         "max_surface_bounces, 32 by default, is the match)")
    ap.add_argument("--nanovdb-convert", default="/tmp/pbrt-v4-build/nanovdb_convert")
    ap.add_argument("--imgtool", default="/tmp/pbrt-v4-build/imgtool")
    ap.add_argument("--nvdb-dir", help="where converted .nvdb and environment files go (default: OUT's folder)")
    a = ap.parse_args()

    with open(a.scene) as fh:
        try:
            sc = json.load(fh)
        except json.JSONDecodeError as e:
            die("%s: malformed JSON: %s" % (a.scene, e))
    scene_dir = os.path.dirname(os.path.abspath(a.scene))
    out_dir = os.path.dirname(os.path.abspath(a.out))
    nvdb_dir = os.path.abspath(a.nvdb_dir) if a.nvdb_dir else out_dir
    image = a.image or os.path.splitext(a.out)[0] + ".exr"

    # Keys that only steer vdbmarch's sampling (its converged image does not depend on them).
    check_keys(sc, {"camera", "lights", "media", "surfaces", "background", "render",
                    "experiments", "photons", "cache", "environment"}, "scene")

    def resolve(p):
        if "#" in p:
            die("file path %r holds the frame token: convert one frame's scene" % p)
        return p if os.path.isabs(p) else os.path.join(scene_dir, p)

    # -------------------------------------------------------------- render
    rd = sc.get("render", {})
    check_keys(rd, {"method", "spp", "step", "shadow_step", "max_depth", "li", "ray_samples", "noise",
                    "denoise", "aovs", "seed", "threads", "max_surface_bounces", "pixel_jitter",
                    "exposure"}, "render")
    spp = a.spp if a.spp else int(rd.get("spp", 1))
    max_depth = int(rd.get("max_depth", 1))
    seed = a.seed if a.seed is not None else int(rd.get("seed", 0))
    jitter = rd.get("pixel_jitter", True)

    # -------------------------------------------------------------- camera
    cam = sc.get("camera", {})
    check_keys(cam, {"type", "position", "look_at", "up", "fov_deg", "resolution"}, "camera")
    if cam.get("type", "perspective") != "perspective":
        die("camera.type: %r is not supported (perspective only)" % cam.get("type"))
    eye = vec3(cam.get("position"), "camera.position", [0, 0, 5])
    look = vec3(cam.get("look_at"), "camera.look_at", [0, 0, 0])
    up = vec3(cam.get("up"), "camera.up", [0, 1, 0])
    fov_v = num(cam.get("fov_deg"), "camera.fov_deg", 40.0)
    W, H = a.resolution if a.resolution else cam.get("resolution", [640, 480])
    if W >= H:
        fov = fov_v  # shorter axis is the vertical one
    else:
        fov = math.degrees(2 * math.atan(math.tan(math.radians(fov_v) / 2) * W / H))

    # -------------------------------------------------------------- media
    media = sc.get("media", [])
    mnames = []
    minfo = {}  # name -> dict
    for i, m in enumerate(media):
        p = "media[%d]" % i
        if not isinstance(m, dict):
            die("%s: expected an object" % p)
        t = m.get("type")
        if t == "homogeneous":
            check_keys(m, {"name", "type", "sigma_a", "sigma_s", "g", "bounds"}, p)
        elif t == "vdb":
            check_keys(m, {"name", "type", "sigma_a", "sigma_s", "g", "file", "grid", "density_scale",
                           "transform", "emission"}, p)
            if "emission" in m:
                die("%s.emission: not supported (pbrt's nanovdb medium has only a peak-normalised "
                    "blackbody emission, not vdbmarch's scale x grid x colour or its Planck brightness)" % p)
        else:
            die("%s.type: %r is not supported" % (p, t))
        name = m.get("name", "medium%d" % i)
        sa = colour(m.get("sigma_a"), p + ".sigma_a", 0)
        ss = colour(m.get("sigma_s"), p + ".sigma_s", 1)
        info = {"name": name, "type": t, "sigma_a": sa, "sigma_s": ss,
                "g": num(m.get("g"), p + ".g", 0.0), "path": p, "vacuum": max(sa + ss) == 0}
        if t == "homogeneous":
            b = m.get("bounds")
            if b is not None:
                check_keys(b, {"min", "max"}, p + ".bounds")
                info["bbox"] = (vec3(b.get("min"), p + ".bounds.min"), vec3(b.get("max"), p + ".bounds.max"))
            else:
                info["bbox"] = None  # all of space
        else:
            if "file" not in m:
                die("%s.file: required" % p)
            src = resolve(m["file"])
            grid = m.get("grid", "density") or "density"
            os.makedirs(nvdb_dir, exist_ok=True)
            dst = os.path.join(nvdb_dir, os.path.splitext(os.path.basename(src))[0] + ".nvdb")
            if not (os.path.exists(dst) and os.path.getmtime(dst) >= os.path.getmtime(src)):
                if not os.access(a.nanovdb_convert, os.X_OK):
                    die("%s.file: needs nanovdb_convert (--nanovdb-convert), not found at %s"
                        % (p, a.nanovdb_convert))
                r = subprocess.run([a.nanovdb_convert, "-f", src, dst], capture_output=True, text=True)
                if r.returncode != 0:
                    die("%s.file: nanovdb_convert %s failed: %s" % (p, src, r.stderr.strip()))
            grids = nvdb_grids(dst)
            if grid not in grids:
                die("%s.grid: no grid %r in %s (grids: %s)" % (p, grid, dst, ", ".join(grids)))
            lo, hi, vs = grids[grid]
            M = transform_matrix(m.get("transform"), p + ".transform")
            # pad by one voxel: vdbmarch interpolates between voxel centres, past the active bbox
            lo = [lo[k] - vs[k] for k in range(3)]
            hi = [hi[k] + vs[k] for k in range(3)]
            info.update({"nvdb": dst, "grid": grid, "M": M, "gridbox": (lo, hi),
                         "scale": num(m.get("density_scale"), p + ".density_scale", 1.0)})
            P, _ = box_mesh(lo, hi, M)
            info["bbox"] = bbox_of(P)
        if name in minfo:
            die("%s.name: duplicate medium name %r" % (p, name))
        minfo[name] = info
        mnames.append(name)

    # -------------------------------------------------------------- surfaces (first pass: geometry)
    surfs = sc.get("surfaces", [])
    sinfo = []
    interior_of = set()
    for i, s in enumerate(surfs):
        p = "surfaces[%d]" % i
        check_keys(s, {"shape", "file", "grid", "isovalue", "transform", "material", "interior",
                       "exterior", "smooth_normals"}, p)
        shape = s.get("shape")
        M = transform_matrix(s.get("transform"), p + ".transform")
        mat = s.get("material", {"type": "dielectric", "ior": 1.5})
        mt = mat.get("type", "dielectric")
        if mt == "dielectric":
            check_keys(mat, {"type", "ior"}, p + ".material")
        elif mt == "diffuse":
            check_keys(mat, {"type", "albedo"}, p + ".material")
        elif mt == "interface":
            check_keys(mat, {"type"}, p + ".material")
        else:
            die("%s.material.type: %r is not supported" % (p, mt))
        d = {"path": p, "shape": shape, "M": M, "mat": mat, "mtype": mt,
             "interior": s.get("interior"), "exterior": s.get("exterior")}
        if shape == "box":
            if "file" in s or "smooth_normals" in s:
                die("%s: file/smooth_normals are not box keys" % p)
            d["P"], d["F"] = box_mesh([-0.5] * 3, [0.5] * 3, M)
            d["N"] = None
            d["bbox"] = bbox_of(d["P"])
        elif shape == "sphere":
            if "file" in s or "smooth_normals" in s:
                die("%s: file/smooth_normals are not sphere keys" % p)
            # bbox of the transformed unit sphere: centre +- row norms of the linear part
            c = [M[k][3] for k in range(3)]
            r = [math.sqrt(M[k][0] ** 2 + M[k][1] ** 2 + M[k][2] ** 2) for k in range(3)]
            d["bbox"] = ([c[k] - r[k] for k in range(3)], [c[k] + r[k] for k in range(3)])
        elif shape == "mesh":
            if "file" not in s:
                die("%s.file: required for a mesh" % p)
            fn = resolve(s["file"])
            if not fn.lower().endswith(".obj"):
                die("%s.file: only .obj meshes are supported by the converter (got %s)" % (p, fn))
            P, F = read_obj(fn, p + ".file")
            P = [xform_point(M, q) for q in P]
            closed = is_closed(F)
            if closed and signed_volume(P, F) < 0:
                F = [[x, z, y] for x, y, z in F]
            if not closed and (d["interior"] or mt == "dielectric"):
                warn("%s: open mesh with glass or an interior: inside/outside follow the file's winding" % p)
            d["P"], d["F"] = P, F
            d["N"] = vertex_normals(P, F) if s.get("smooth_normals", False) else None
            d["bbox"] = bbox_of(P)
        else:
            die("%s.shape: %r is not supported" % (p, shape))
        if d["interior"] is not None:
            if d["interior"] not in minfo:
                die("%s.interior: no medium named %r" % (p, d["interior"]))
            interior_of.add(d["interior"])
        if d["exterior"] is not None and d["exterior"] not in minfo:
            die("%s.exterior: no medium named %r" % (p, d["exterior"]))
        sinfo.append(d)

    def inside(b, box):  # bbox b within box
        return all(box[0][k] <= b[0][k] and b[1][k] <= box[1][k] for k in range(3))

    def disjoint(b, box):
        return any(b[1][k] <= box[0][k] or box[1][k] <= b[0][k] for k in range(3))

    world = [n for n in mnames if n not in interior_of and not minfo[n]["vacuum"]]
    for i, n1 in enumerate(world):
        for n2 in world[i + 1:]:
            b1, b2 = minfo[n1]["bbox"], minfo[n2]["bbox"]
            if b1 is None or b2 is None or not disjoint(b1, b2):
                die("media: world media %r and %r overlap (%s, %s); pbrt cannot add media up"
                    % (n1, n2, minfo[n1]["path"], minfo[n2]["path"]))
    for n in interior_of:
        mi = minfo[n]
        if mi["type"] == "homogeneous" and mi["bbox"] is not None:
            for d in sinfo:
                if d["interior"] == n and not inside(d["bbox"], mi["bbox"]):
                    die("%s.bounds: medium %r is an interior clipped by its bounds; pbrt cannot clip"
                        % (mi["path"], n))

    def world_medium_around(b, what):
        """The world medium holding bbox b: name, "" (vacuum) or error when b straddles one."""
        for n in world:
            box = minfo[n]["bbox"]
            if box is None or inside(b, box):
                return n
            if not disjoint(b, box):
                die("%s: straddles the bounds of world medium %r; pbrt needs it wholly in or out"
                    % (what, n))
        return ""

    def point_in_surface(pt, d):
        if d["shape"] == "sphere":
            Mi = inverse_affine(d["M"])
            q = xform_point(Mi, pt)
            return dot(q, q) < 1
        if d["shape"] == "box":
            q = xform_point(inverse_affine(d["M"]), pt)
            return all(abs(x) < 0.5 for x in q)
        lo, hi = d["bbox"]
        if all(lo[k] < pt[k] < hi[k] for k in range(3)):
            die("%s: the camera is inside this mesh's bounding box; the converter cannot tell "
                "which medium it starts in" % d["path"])
        return False

    # camera medium: the innermost surface holding the camera, else the world medium there
    cam_medium = ""
    holders = [d for d in sinfo if point_in_surface(eye, d)]
    if holders:
        holders.sort(key=lambda d: (d["bbox"][1][0] - d["bbox"][0][0]) * (d["bbox"][1][1] - d["bbox"][0][1])
                     * (d["bbox"][1][2] - d["bbox"][0][2]))
        cam_medium = holders[0]["interior"] or ""
    else:
        for n in world:
            box = minfo[n]["bbox"]
            if box is None or all(box[0][k] < eye[k] < box[1][k] for k in range(3)):
                cam_medium = n

    # -------------------------------------------------------------- lights
    lines_l = []
    delta_lights = 0
    for i, L in enumerate(sc.get("lights", [])):
        p = "lights[%d]" % i
        t = L.get("type") if isinstance(L, dict) else None
        if t == "point":
            check_keys(L, {"type", "position", "intensity"}, p)
            I = colour(L.get("intensity"), p + ".intensity", 1)
            lines_l.append('LightSource "point" "point3 from" [ %s ] "rgb I" [ %s ]'
                           % (fl(vec3(L.get("position"), p + ".position")), fl(I)))
            delta_lights += 1
        elif t == "spot":
            check_keys(L, {"type", "position", "direction", "intensity", "cone_deg", "falloff_deg"}, p)
            pos = vec3(L.get("position"), p + ".position")
            dr = vec3(L.get("direction"), p + ".direction")
            cone = num(L.get("cone_deg"), p + ".cone_deg", 30.0)
            fall = num(L.get("falloff_deg"), p + ".falloff_deg", min(5.0, cone))
            I = colour(L.get("intensity"), p + ".intensity", 1)
            lines_l.append('LightSource "spot" "point3 from" [ %s ] "point3 to" [ %s ] "rgb I" [ %s ]'
                           ' "float coneangle" %s "float conedeltaangle" %s'
                           % (fl(pos), fl(add(pos, dr)), fl(I), f(cone), f(fall)))
            delta_lights += 1
        elif t == "directional":
            check_keys(L, {"type", "direction", "irradiance"}, p)
            dr = vec3(L.get("direction"), p + ".direction")
            E = colour(L.get("irradiance"), p + ".irradiance", 1)
            lines_l.append('LightSource "distant" "point3 from" [ 0 0 0 ] "point3 to" [ %s ] "rgb L" [ %s ]'
                           % (fl(dr), fl(E)))
            delta_lights += 1
        elif t == "sphere":
            check_keys(L, {"type", "position", "radius", "power"}, p)
            pos = vec3(L.get("position"), p + ".position")
            r = num(L.get("radius"), p + ".radius", 1.0)
            P = colour(L.get("power"), p + ".power", 1)
            Lr = [x / (4 * math.pi ** 2 * r * r) for x in P]
            b = ([pos[k] - r for k in range(3)], [pos[k] + r for k in range(3)])
            world_medium_around(b, p)  # only checks that it does not straddle a medium's bounds
            lines_l.append("AttributeBegin  # %s: power %s W -> radiance power/(4 pi^2 r^2)\n"
                           "  Translate %s\n"
                           '  Material "diffuse" "rgb reflectance" [ 0 0 0 ]\n'
                           '  AreaLightSource "diffuse" "rgb L" [ %s ]\n'
                           '  Shape "sphere" "float radius" %s\n'
                           "AttributeEnd" % (p, fl(P), fl(pos), fl(Lr), f(r)))
        elif t == "collimated_quad":
            die("%s.type: collimated_quad has no pbrt-v4 counterpart" % p)
        else:
            die("%s.type: %r is not supported" % (p, t))

    bg = colour(sc.get("background"), "background", 0)
    if "environment" in sc:
        env = sc["environment"]
        check_keys(env, {"file", "scale", "rotation"}, "environment")
        if max(bg) > 0:
            die("background: a non-black background together with environment")
        if "file" not in env:
            die("environment.file: required")
        src = resolve(env["file"])
        os.makedirs(nvdb_dir, exist_ok=True)
        dst = os.path.join(nvdb_dir, os.path.splitext(os.path.basename(src))[0] + "_equiarea.exr")
        if not (os.path.exists(dst) and os.path.getmtime(dst) >= os.path.getmtime(src)):
            if not os.access(a.imgtool, os.X_OK):
                die("environment.file: needs pbrt's imgtool (--imgtool), not found at %s" % a.imgtool)
            r = subprocess.run([a.imgtool, "makeequiarea", src, "--outfile", dst], capture_output=True, text=True)
            if r.returncode != 0:
                die("environment.file: imgtool makeequiarea %s failed: %s" % (src, r.stderr.strip()))
        # vdbmarch: texel (u, v) looks along (sin t sin p, cos t, -sin t cos p), t = pi v, p = 2 pi u;
        # pbrt's makeequiarea puts it at light-space (sin t cos p, sin t sin p, cos t): world x = light y,
        # world y = light z, world z = -light x; then the map's rotation about +y (right-handed).
        Mw = [[0, 1, 0, 0], [0, 0, 1, 0], [-1, 0, 0, 0], [0, 0, 0, 1]]
        lines_l.append("AttributeBegin  # environment: %s as an equal-area map" % src)
        lines_l.append("  Rotate %s 0 1 0" % f(num(env.get("rotation"), "environment.rotation", 0.0)))
        lines_l.append("  " + pbrt_transform(Mw))
        lines_l.append('  LightSource "infinite" "string filename" "%s" "float scale" %s'
                       % (dst, f(num(env.get("scale"), "environment.scale", 1.0))))
        lines_l.append("AttributeEnd")
    elif max(bg) > 0:
        lines_l.append('LightSource "infinite" "rgb L" [ %s ]' % fl(bg))

    # -------------------------------------------------------------- write
    has_glass = any(d["mtype"] == "dielectric" and d["mat"].get("ior", 1.5) != 1 for d in sinfo)
    pbrt_depth = a.max_depth if a.max_depth else max_depth
    if has_glass and delta_lights:
        warn("a point/spot/directional light with refracting glass: pbrt's volpath cannot carry a "
             "delta light through glass (vdbmarch adds those caustics from photons)")
    if has_glass and not a.max_depth and a.specular_depth is None:
        warn("pbrt's maxdepth also counts glass reflections/refractions, vdbmarch's max_depth does not: "
             "paths through glass are cut earlier in pbrt (raise it with --max-depth)")

    o = []
    o.append("# pbrt-v4 scene converted from %s by tools/pbrt/vdbmarch_to_pbrt.py" % os.path.abspath(a.scene))
    o.append("# vdbmarch fov_deg %s (vertical) -> pbrt fov %s (shorter axis)" % (f(fov_v), f(fov)))
    if cam_medium:
        o.append('MediumInterface "" "%s"  # the camera starts in this medium' % cam_medium)
    o.append("Scale -1 1 1  # pbrt is left-handed: mirror x so the image is not flipped")
    o.append("LookAt %s   %s   %s" % (fl(eye), fl(look), fl(up)))
    o.append('Camera "perspective" "float fov" %s' % f(fov))
    o.append('Sampler "zsobol" "integer pixelsamples" %d "integer seed" %d' % (spp, seed % 2147483647))
    o.append('Integrator "volpath" "integer maxdepth" %d' % pbrt_depth
             + ('' if a.specular_depth is None else ' "integer maxspeculardepth" %d' % a.specular_depth))
    o.append('Film "rgb" "integer xresolution" %d "integer yresolution" %d "string filename" "%s"'
             ' "bool savefp16" false' % (W, H, image))
    o.append('PixelFilter "box"' + ("" if jitter else ' "float xradius" 0.0001 "float yradius" 0.0001'))
    o.append("WorldBegin")
    o.append("")
    for n in mnames:
        mi = minfo[n]
        if mi["vacuum"]:
            continue
        common = '"rgb sigma_a" [ %s ] "rgb sigma_s" [ %s ] "float g" %s' % (
            fl(mi["sigma_a"]), fl(mi["sigma_s"]), f(mi["g"]))
        if mi["type"] == "homogeneous":
            o.append('MakeNamedMedium "%s" "string type" "homogeneous" %s "float scale" 1' % (n, common))
        else:
            o.append("AttributeBegin  # %s: grid world space, then the medium's transform" % mi["path"])
            o.append("  " + pbrt_transform(mi["M"]))
            o.append('  MakeNamedMedium "%s" "string type" "nanovdb" "string filename" "%s"' % (n, mi["nvdb"]))
            o.append('    "string gridname" "%s" %s "float scale" %s' % (mi["grid"], common, f(mi["scale"])))
            o.append("AttributeEnd")
    o.append("")
    for n in world:
        mi = minfo[n]
        if mi["bbox"] is None:
            continue  # unbounded: the camera medium and every surface's exterior
        if mi["type"] == "homogeneous":
            lo, hi = mi["bbox"]
            # grow by a hair so that faces shared with opaque surfaces (a floor under the fog)
            # lie inside them and are never hit first
            eps = 1e-4 * max(hi[k] - lo[k] for k in range(3))
            P, F = box_mesh([x - eps for x in lo], [x + eps for x in hi])
        else:
            P, F = box_mesh(mi["gridbox"][0], mi["gridbox"][1], mi["M"])
        o.append("AttributeBegin  # where world medium %r is (%s)" % (n, mi["path"]))
        o.append('  MediumInterface "%s" ""' % n)
        o.append('  Material "interface"')
        o.append(trianglemesh(P, F).rstrip("\n"))
        o.append("AttributeEnd")
    o.append("")
    o.extend(lines_l)
    o.append("")
    for d in sinfo:
        p, mt = d["path"], d["mtype"]
        interior = d["interior"] or ""
        if interior and minfo[interior]["vacuum"]:
            interior = ""
        if d["exterior"] is not None:
            exterior = d["exterior"]
        elif mt == "diffuse" and not interior:
            exterior = None  # opaque, nothing inside: keeps whatever medium the ray is in
        else:
            exterior = world_medium_around(d["bbox"], p)
        if exterior is not None and exterior and minfo[exterior]["vacuum"]:
            exterior = ""
        if mt == "interface" and interior == (exterior or ""):
            continue  # changes nothing
        o.append("AttributeBegin  # %s" % p)
        if exterior is not None:
            o.append('  MediumInterface "%s" "%s"' % (interior, exterior))
        if mt == "diffuse":
            alb = colour(d["mat"].get("albedo"), p + ".material.albedo", 0.5)
            o.append('  Material "diffuse" "rgb reflectance" [ %s ]' % fl(alb))
        elif mt == "dielectric":
            o.append('  Material "dielectric" "float eta" %s' % f(num(d["mat"].get("ior"), p + ".material.ior", 1.5)))
        else:
            o.append('  Material "interface"')
        if d["shape"] == "sphere":
            o.append("  " + pbrt_transform(d["M"]))
            o.append('  Shape "sphere" "float radius" 1')
        else:
            o.append(trianglemesh(d["P"], d["F"], d["N"]).rstrip("\n"))
        o.append("AttributeEnd")
    with open(a.out, "w") as fh:
        fh.write("\n".join(o) + "\n")


if __name__ == "__main__":
    main()
