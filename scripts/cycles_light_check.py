"""Measure Cycles' light conventions against closed forms (the evidence for cycles_render.py's
point, sphere and spot export; docs/validation/cycles.md "Point, sphere and spot lights").

    blender -b --factory-startup -P scripts/cycles_light_check.py -- [--size 64] [--spp 64]
        [--runs 4] [--seed 1000] [--threads 0] [--only CASE,...] [--out DIR]
        [--mesh-subdivisions 6] [--mesh-shuffle SEED] [--mesh-no-nee]

Every case is a Lambertian plane z = 0 (Diffuse BSDF, albedo RHO = 0.5) seen straight down by an
orthographic camera below the light (z = 0.5, the square [-1, 1]^2, box filter one pixel wide),
lit by one light at height 1 and nothing else (black world, no other surface: the plane cannot
see itself), so that a pixel is RHO / pi times the irradiance E(x, y) averaged over the pixel.
The closed form of E is integrated over the same square by the midpoint rule (16 x 16 points per
pixel); each row gives the image mean of Cycles (mean and standard error over `runs` seeds), the
closed form's, their ratio, z = (Cycles - closed form) / SE and the largest relative difference
of a lit pixel (noise included). `setting` is what Blender is given, `model` the closed form.
Cases, first Blender's own lights (the conventions), then cycles_render.py's export:

  sun          Sun, strength S = 2, straight down: E = S (the chain: albedo, camera, film)
  point        Point, power P = 100 W, radius 0: E = (P / 4 pi) cos / d^2
  point-r      Point, power P, radius r = 0.3: a disc of radius r through the centre facing the
               shading point, radiance P / (4 pi^2 r^2): E = (P / 4 pi) cos / (d^2 + r^2);
               `as sphere` holds the same image to a sphere of the same far-field intensity,
               E = (P / 4 pi) cos / d^2, which it is not
  spot         Spot, power P, spot_size 60 deg, blend 0.5, straight down: Cycles 3.4's rule
               I = (P / 4 pi) c smoothstep((c - cos o) / ((1 - cos o) blend)) (c the cosine to
               the axis, no smoothstep once c - cos o >= (1 - cos o) blend); `as KHR` holds it to
               KHR_lights_punctual's falloff with the same outer angle and its inner angle where
               Cycles' ramp ends, which it is not
  mesh-sphere  an icosphere (--mesh-subdivisions, Blender's count: 6 is 20,480 faces, vertices
               on the sphere) of an Emission shader of strength L = 2, sampled as a light:
               E = pi L (r / d)^2 cos for the sphere (the mesh's area ratio is printed; its mean
               projected area is that ratio times pi r^2); --mesh-shuffle permutes the faces'
               order, which the physics does not see and Cycles 3.4's light sampling does
  export-point cycles_render.point_light, intensity I = 8: E = I cos / d^2
  export-spot  cycles_render.point_light with a spot (inner 15, outer 35 deg, axis tilted by
               21 deg): E = I clamp((c - cos o) / (cos i - cos o), 0, 1)^2 cos / d^2 (core/light.h)
  export-sphere cycles_render.sphere_light, radiance L = 2, radius 0.3: E = pi L (r / d)^2 cos
"""

import argparse
import math
import os
import sys
import tempfile
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_render  # noqa: E402  (the exporter's own point_light and sphere_light)

RHO = 0.5
H = 1.0        # the light's height above the plane
P = 100.0      # Blender power [W]
R = 0.3        # radius of point-r and mesh-sphere
L_MESH = 2.0   # the mesh sphere's radiance
I_SSSLAB = 8.0  # the exported point and spot lights' intensity [per sr]


def args_after_dashes():
    argv = sys.argv
    argv = argv[argv.index("--") + 1:] if "--" in argv else []
    p = argparse.ArgumentParser(prog="cycles_light_check.py")
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--runs", type=int, default=4)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--only", default="")
    p.add_argument("--seed", type=int, default=1000, help="the first run's seed (then +1, +2, ...)")
    p.add_argument("--out", default="")
    p.add_argument("--mesh-subdivisions", type=int, default=6,
                   help="mesh-sphere: Blender's icosphere subdivisions (6: 20,480 faces)")
    p.add_argument("--mesh-shuffle", type=int, default=-1,
                   help="mesh-sphere: permute the faces' order with this seed (physics ignores it)")
    p.add_argument("--mesh-no-nee", action="store_true",
                   help="mesh-sphere: not sampled as a light (material.cycles.sample_as_light off, "
                        "as cycles_render.py exports a sphere light)")
    return p.parse_args(argv)


def smoothstep(x):
    return x * x * (3 - 2 * x)


def khr_factor(c, inner_deg, outer_deg):
    ci, co = math.cos(math.radians(inner_deg)), math.cos(math.radians(outer_deg))
    scale = 1 / max(0.001, ci - co)
    return np.clip(c * scale - co * scale, 0, 1) ** 2


def cycles_spot_factor(c, size, blend):
    ca = math.cos(size / 2)
    smooth = (1 - ca) * blend
    t = c - ca
    f = np.where(t < smooth, smoothstep(np.clip(t / smooth, 0, 1)), 1.0) if smooth > 0 else 1.0
    return np.where(c > ca, c * f, 0.0)


def geometry(x, y, light):
    v = np.stack([x - light[0], y - light[1], -np.full_like(x, light[2])], axis=-1)
    d = np.linalg.norm(v, axis=-1)
    cos_recv = light[2] / d  # receiver normal +z, light above
    return v / d[..., None], d, cos_recv


def tilted_axis():
    a = np.array([0.35, 0.1, -1.0])
    return a / np.linalg.norm(a)


SPOT_SIZE, SPOT_BLEND = 2 * math.radians(30), 0.5
KHR_INNER, KHR_OUTER = 15.0, 35.0


def spot_inner_of_cycles_ramp():
    # The angle where Cycles' ramp ends: cos = cos o + (1 - cos o) blend.
    co = math.cos(SPOT_SIZE / 2)
    return math.degrees(math.acos(co + (1 - co) * SPOT_BLEND))


def closed_forms(name, x, y):
    """Irradiance E(x, y) of each model a case is held to: {label: E}."""
    lp = (0.0, 0.0, H)
    w, d, cr = geometry(x, y, lp)
    if name == "sun":
        return {"E = S": np.full_like(x, 2.0)}
    if name == "point":
        return {"I = P/(4 pi)": P / (4 * math.pi) * cr / d**2}
    if name == "point-r":
        return {"disc: I = P/(4 pi), cos/(d^2+r^2)": P / (4 * math.pi) * cr / (d**2 + R**2),
                "as sphere: I = P/(4 pi), cos/d^2": P / (4 * math.pi) * cr / d**2}
    if name == "mesh-sphere":
        return {"E = pi L (r/d)^2 cos": math.pi * L_MESH * (R / d) ** 2 * cr}
    if name == "spot":
        c = w @ np.array([0.0, 0.0, -1.0])
        inner = spot_inner_of_cycles_ramp()
        return {"Cycles: (P/4pi) c smoothstep": P / (4 * math.pi) * cycles_spot_factor(c, SPOT_SIZE, SPOT_BLEND) * cr / d**2,
                f"as KHR (inner {inner:.2f}, outer 30)": P / (4 * math.pi) * khr_factor(c, inner, 30.0) * cr / d**2}
    if name == "export-point":
        return {"E = I cos/d^2": I_SSSLAB * cr / d**2}
    if name == "export-spot":
        c = w @ tilted_axis()
        return {f"E = I KHR(c) cos/d^2": I_SSSLAB * khr_factor(c, KHR_INNER, KHR_OUTER) * cr / d**2}
    if name == "export-sphere":
        return {"E = pi L (r/d)^2 cos": math.pi * L_MESH * (R / d) ** 2 * cr}
    raise KeyError(name)


SETTINGS = {
    "sun": "Sun, strength 2, down",
    "point": f"Point, power {P:g} W, radius 0, height {H:g}",
    "point-r": f"Point, power {P:g} W, radius {R:g}, height {H:g}",
    "mesh-sphere": f"icosphere radius {R:g}, Emission strength {L_MESH:g}, sampled as a light (options: --mesh-*)",
    "spot": f"Spot, power {P:g} W, spot_size 60 deg, blend {SPOT_BLEND:g}, down",
    "export-point": f"cycles_render.point_light, I = {I_SSSLAB:g}: Point, power 4 pi I, radius 0",
    "export-spot": f"cycles_render.point_light, I = {I_SSSLAB:g}, spot inner {KHR_INNER:g}, outer {KHR_OUTER:g}, tilted",
    "export-sphere": f"cycles_render.sphere_light, L = {L_MESH:g}, r = {R:g}: icosphere (81,920 faces), Emission, not sampled as a light",
}


def build(name, a):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    from mathutils import Vector

    mat = cycles_render.diffuse_material({"name": "lambert", "albedo": (RHO, RHO, RHO)})
    s = 1.5
    me = bpy.data.meshes.new("plane")
    me.from_pydata([(-s, -s, 0), (s, -s, 0), (s, s, 0), (-s, s, 0)], [], [(0, 1, 2, 3)])
    me.materials.append(mat)
    ob = bpy.data.objects.new("plane", me)
    scene.collection.objects.link(ob)

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world

    def add_light(ld, pos, axis=(0, 0, -1)):
        lo = bpy.data.objects.new(ld.name, ld)
        lo.location = pos
        lo.rotation_mode = "QUATERNION"
        lo.rotation_quaternion = (-Vector(axis)).to_track_quat("Z", "Y")  # lights shine along -Z
        scene.collection.objects.link(lo)

    if name == "sun":
        ld = bpy.data.lights.new("sun", type="SUN")
        ld.energy = 2.0
        ld.angle = 0.0
        add_light(ld, (0, 0, H))
    elif name in ("point", "point-r"):
        ld = bpy.data.lights.new(name, type="POINT")
        ld.energy = P
        ld.shadow_soft_size = R if name == "point-r" else 0.0
        add_light(ld, (0, 0, H))
    elif name == "spot":
        ld = bpy.data.lights.new("spot", type="SPOT")
        ld.energy = P
        ld.shadow_soft_size = 0.0
        ld.spot_size = SPOT_SIZE
        ld.spot_blend = SPOT_BLEND
        add_light(ld, (0, 0, H))
    elif name == "export-point":
        cycles_render.point_light(scene, name, (0, 0, H), [I_SSSLAB] * 3)
    elif name == "export-spot":
        cycles_render.point_light(scene, name, (0, 0, H), [I_SSSLAB] * 3,
                                  spot=(tuple(tilted_axis()), KHR_INNER, KHR_OUTER))
    elif name == "export-sphere":
        cycles_render.sphere_light(scene, name, (0, 0, H), R, [L_MESH] * 3)
        sm = bpy.data.objects[name].data
        area = sum(p.area for p in sm.polygons)
        print(f"cycles_light_check.py: export-sphere {len(sm.polygons)} faces, area / (4 pi r^2) = "
              f"{area / (4 * math.pi * R * R):.6f}")
    elif name == "mesh-sphere":
        import bmesh

        bm = bmesh.new()
        bmesh.ops.create_icosphere(bm, subdivisions=a.mesh_subdivisions, radius=R)
        sm = bpy.data.meshes.new("emitter")
        bm.to_mesh(sm)
        bm.free()
        if a.mesh_shuffle >= 0:
            verts = [tuple(v.co) for v in sm.vertices]
            faces = [tuple(f.vertices) for f in sm.polygons]
            order = np.random.default_rng(a.mesh_shuffle).permutation(len(faces))
            sm = bpy.data.meshes.new("emitter_shuffled")
            sm.from_pydata(verts, [], [faces[i] for i in order])
        em_mat, ent, o2 = cycles_render.node_material("emission")
        em = ent.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = (1, 1, 1, 1)
        em.inputs["Strength"].default_value = L_MESH
        ent.links.new(em.outputs[0], o2.inputs["Surface"])
        em_mat.cycles.sample_as_light = not a.mesh_no_nee
        sm.materials.append(em_mat)
        so = bpy.data.objects.new("emitter", sm)
        so.location = (0, 0, H)
        scene.collection.objects.link(so)
        # Facets: the mesh's area over the sphere's (its mean projected area over pi r^2, Cauchy).
        area = sum(p.area for p in sm.polygons)
        radii = [v.co.length for v in sm.vertices]
        print(f"cycles_light_check.py: mesh-sphere {len(sm.polygons)} faces, area / (4 pi r^2) = "
              f"{area / (4 * math.pi * R * R):.6f}, vertex radius {min(radii):.6f}..{max(radii):.6f}")

    cam = bpy.data.cameras.new("camera")
    cam.type = "ORTHO"
    cam.ortho_scale = 2.0
    cam.sensor_fit = "HORIZONTAL"
    cam.clip_start = 1e-3
    cam.clip_end = 10
    co = bpy.data.objects.new("camera", cam)
    co.location = (0, 0, 0.5)  # below every light: the camera sees the plane only
    scene.collection.objects.link(co)
    scene.camera = co

    cycles_render.unbiased_settings(scene, a.size, a.size, a.spp, a.threads, 0)
    return scene


def render_mean(scene, path, seed):
    scene.cycles.seed = seed
    scene.render.filepath = path
    t = time.monotonic()
    bpy.ops.render.render(write_still=True)
    dt = time.monotonic() - t
    img = bpy.data.images.load(path, check_existing=False)
    px = np.array(img.pixels[:], dtype=np.float64).reshape(img.size[1], img.size[0], img.channels)
    bpy.data.images.remove(img)
    return px[..., :3].mean(axis=-1), dt


def main():
    a = args_after_dashes()
    names = a.only.split(",") if a.only else list(SETTINGS)
    out = a.out or tempfile.mkdtemp(prefix="cycles_light_check_")
    os.makedirs(out, exist_ok=True)
    n = a.size
    sub = 16
    u = (np.arange(n * sub) + 0.5) / (n * sub) * 2 - 1
    x, y = np.meshgrid(u, u)  # row 0 = y = -1: Blender's pixels run bottom to top
    rows = []
    for name in names:
        scene = build(name, a)
        imgs, secs = [], 0.0
        for k in range(a.runs):
            img, dt = render_mean(scene, os.path.join(out, f"{name}_{k}.exr"), a.seed + k)
            imgs.append(img)
            secs += dt
        means = np.array([im.mean() for im in imgs])
        m = means.mean()
        se = means.std(ddof=1) / math.sqrt(len(means)) if len(means) > 1 else float("nan")
        img = np.mean(imgs, axis=0)
        for label, E in closed_forms(name, x, y).items():
            cf_img = RHO / math.pi * E.reshape(n, sub, n, sub).mean(axis=(1, 3))
            cf = cf_img.mean()
            lit = cf_img > 0.05 * cf_img.max()
            rel = np.abs(img[lit] / cf_img[lit] - 1)
            z = (m - cf) / se if se > 0 else (0.0 if m == cf else math.copysign(math.inf, m - cf))
            rows.append((name, SETTINGS[name], label, cf, m, se, m / cf, z, float(rel.max()), secs))
            print(f"cycles_light_check.py: {name}: {label}: closed form {cf:.7f}, Cycles {m:.7f} +- {se:.1e}, "
                  f"ratio {m / cf:.6f}, z {z:.2f}, worst lit pixel |rel| {rel.max():.4f}, {secs:.1f} s",
                  flush=True)
    print(f"\n{n} x {n}, {a.spp} spp, {a.runs} runs (Blender {bpy.app.version_string}); images in {out}")
    print("| case | Blender setting | model | closed form mean | Cycles mean +- SE | ratio | z | worst lit pixel rel. diff | Cycles s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]:.7f} | {r[4]:.7f} +- {r[5]:.1e} | {r[6]:.6f} | {r[7]:.2f} | {r[8]:.4f} | {r[9]:.1f} |")


main()
