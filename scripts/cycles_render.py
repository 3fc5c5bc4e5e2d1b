"""Render an exported ssslab scene with Blender's Cycles, as an independent reference.

    blender -b --factory-startup -P scripts/cycles_render.py -- \\
        <exported>/<scene>/scene.json out.exr --spp 64 --seed 1 [--width W --height H]

<exported> is what `ssslab scene <scene.toml> --export-obj <exported>` writes: every shape's
tessellation in world units and scene.json (camera, lights, materials per world unit). This script
rebuilds that scene in Cycles so that both renderers solve the same problem:

- meshes as exported (flat shading: ssslab uses geometric normals), coordinates unchanged;
- a medium: Glass BSDF (GGX, Cycles roughness = sqrt(alpha), as Cycles squares it) with the
  medium's index, and a homogeneous volume of Volume Scatter (colour sigma_s / D, density D, one
  node per channel when g differs between channels) plus Volume Absorption (colour 1 - sigma_a / D,
  density D): Cycles' sigma_s = colour x density and sigma_a = (1 - colour) x density;
- diffuse: Diffuse BSDF (Lambert, roughness 0);
- directional light: a Sun with strength = irradiance facing it and angle = twice the angular
  radius (Cycles' sun strength is that irradiance); environment: a constant world colour;
- point light (intensity I per sr): a Point of radius 0 and power 4 pi max(I) [W], colour
  I / max(I): Cycles 3.4's point light of power P has the intensity P / (4 pi) (measured: a
  Lambertian plane under it gives the closed form E = (P / 4 pi) cos / d^2 to 3e-7, float
  rounding);
- spot light: the same Point (power 4 pi times the intensity on the axis, radius 0) with a light
  shader whose Emission strength is KHR_lights_punctual's falloff of core/light.h,
  clamp((c - cos outer) / max(0.001, cos inner - cos outer), 0, 1)^2, c = Geometry.Normal . axis
  (the normal of a lamp's shading point in Cycles is the unit vector from the light towards the
  point lit; measured against the closed form with a tilted axis, ratio 1.0000). Not Cycles'
  Spot: its intensity is (P / 4 pi) c smoothstep((c - cos(spot_size / 2)) / ((1 - cos) blend)),
  an extra factor c and a smoothstep instead of a square (measured: 6.7 % off KHR's falloff on
  the same cone), which no spot_size and spot_blend make equal to KHR's;
- sphere light (radiance L, radius r): an icosphere of 81,920 faces (vertices on the sphere, area
  0.999925 of the sphere's) with an Emission shader of strength max(L), colour L / max(L)
  (Cycles' emission strength is radiance: measured pi L (r / d)^2 cos on a plane), not sampled
  as a light: BSDF and phase-function rays find it, next-event estimation does not, so Cycles is
  unbiased here but noisy for small lights. Opaque and black, like ssslab's sphere light, which
  ends the paths and shadow rays that meet it. Not Cycles' Point with a radius: that is a disc
  of radius r through the centre facing the shading point, radiance P / (4 pi^2 r^2), so that a
  surface facing it at distance d receives (P / 4 pi) / (d^2 + r^2) where a sphere of the same
  intensity gives (P / 4 pi) / d^2 (measured: 0.941 of the sphere's on a plane 1 below a light
  of radius 0.3), and partly occluded or seen directly it is a disc. Nor the icosphere sampled
  as a light: with next-event estimation Cycles 3.4's estimate depends on the order of the
  mesh's faces (measured on 20,480 faces: 0.990 to 1.008 of the closed form for four orders of
  the same faces, where BSDF sampling alone gives 0.9997 +- 0.0010, the same mean for two
  orders); the float rounding of its light distribution's cumulative areas explains 1e-5 of that;
- camera: pinhole, vertical field of view, the scene's up vector; box pixel filter one pixel
  wide (ssslab samples the pixel uniformly);
- every bounce limit at Cycles' maximum (1024), no clamping, no glossy filter, no adaptive
  sampling, no denoising, light threshold 0; linear EXR output (no view transform).

The evidence for the point, spot and sphere conversions is scripts/cycles_light_check.py (a
Lambertian plane under each light in Cycles against the closed form of its irradiance) and the
side-by-sides of experiments/scenes/cycles/{point,spot,sphere}-plane.toml against ssslab; both in
docs/validation/cycles.md, "Point, sphere and spot lights".
"""

import argparse
import json
import math
import os
import sys
import time

import bpy  # noqa: E402  (only inside Blender)


def fail(msg):
    print(f"cycles_render.py: error: {msg}", file=sys.stderr)
    sys.exit(2)


def args_after_dashes():
    argv = sys.argv
    argv = argv[argv.index("--") + 1:] if "--" in argv else []
    p = argparse.ArgumentParser(prog="cycles_render.py")
    p.add_argument("scene_json")
    p.add_argument("out_exr")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--width", type=int, default=0)
    p.add_argument("--height", type=int, default=0)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--passes", action="store_true",
                   help="multilayer EXR with the light passes (diffuse, glossy, transmission, "
                        "environment; direct and indirect) beside Combined")
    p.add_argument("--native-lights", action="store_true",
                   help="a diagnostic, not a reference: spot lights as Cycles' Spot (spot_size 2 x "
                        "outer, the blend where its ramp spans KHR's, power 4 pi I) and sphere lights "
                        "as Cycles' Point with their radius (power 4 pi^2 r^2 L), the approximations "
                        "the default export avoids (docs/validation/cycles.md)")
    return p.parse_args(argv)


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append(tuple(float(x) for x in line.split()[1:4]))
            elif line.startswith("f "):
                faces.append(tuple(int(t.split("/")[0]) - 1 for t in line.split()[1:]))
    return verts, faces


def node_material(name):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    return m, nt, out


def medium_material(d):
    m, nt, out = node_material(d["name"])
    glass = nt.nodes.new("ShaderNodeBsdfGlass")
    glass.distribution = "GGX"
    alpha = float(d["ggx_alpha"])
    glass.inputs["Roughness"].default_value = math.sqrt(alpha)
    glass.inputs["IOR"].default_value = float(d["eta"])
    glass.inputs["Color"].default_value = (1, 1, 1, 1)
    if float(d["eta"]) == 1.0:
        # Index-matched: no boundary at all (ssslab ignores the roughness there).
        surf = nt.nodes.new("ShaderNodeBsdfTransparent")
        surf.inputs["Color"].default_value = (1, 1, 1, 1)
        nt.links.new(surf.outputs[0], out.inputs["Surface"])
    else:
        nt.links.new(glass.outputs[0], out.inputs["Surface"])
    if "density_vdb" in d:
        fail(f"material {d['name']}: heterogeneous (OpenVDB) media are not exported to Cycles")
    sa, ss, g = d["sigma_a_per_unit"], d["sigma_s_per_unit"], d["g"]
    closures = []
    if max(ss) > 0:
        groups = [[0, 1, 2]] if g[0] == g[1] == g[2] else [[0], [1], [2]]
        for ch in groups:
            dens = max(ss[c] for c in ch)
            if dens <= 0:
                continue
            col = [ss[c] / dens if c in ch else 0.0 for c in range(3)]
            sc = nt.nodes.new("ShaderNodeVolumeScatter")
            sc.inputs["Color"].default_value = (*col, 1)
            sc.inputs["Density"].default_value = dens
            sc.inputs["Anisotropy"].default_value = g[ch[0]]
            closures.append(sc)
    if max(sa) > 0:
        dens = max(sa)
        ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
        ab.inputs["Color"].default_value = (*[1 - a / dens for a in sa], 1)
        ab.inputs["Density"].default_value = dens
        closures.append(ab)
    if closures:
        acc = closures[0].outputs[0]
        for c in closures[1:]:
            add = nt.nodes.new("ShaderNodeAddShader")
            nt.links.new(acc, add.inputs[0])
            nt.links.new(c.outputs[0], add.inputs[1])
            acc = add.outputs[0]
        nt.links.new(acc, out.inputs["Volume"])
    m.cycles.homogeneous_volume = True
    m.cycles.volume_sampling = "MULTIPLE_IMPORTANCE"
    return m


def diffuse_material(d):
    m, nt, out = node_material(d["name"])
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*d["albedo"], 1)
    bsdf.inputs["Roughness"].default_value = 0.0
    nt.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return m


# Cycles 3.4's point light of power P [W] and radius 0 has the intensity P / (4 pi) [W/sr] in
# every direction (measured, scripts/cycles_light_check.py): ssslab's intensity I is P = 4 pi I.
POINT_POWER_PER_INTENSITY = 4 * math.pi
# The sphere light's icosphere: Blender's subdivisions 7, 81,920 faces with their vertices on the
# sphere, area (= 4 x mean projected area) 0.999925 of the sphere's.
SPHERE_SUBDIVISIONS = 7


def point_light(scene, name, position, intensity, spot=None):
    """A point light of ssslab intensity I [per sr] (RGB): Cycles' Point, radius 0, power 4 pi
    max(I), colour I / max(I). With spot = (direction, inner_deg, outer_deg) the light's shader
    multiplies it by KHR_lights_punctual's factor clamp(c scale + offset, 0, 1)^2 of core/light.h,
    c = Geometry.Normal . direction: a lamp's normal in Cycles is the unit vector from the light to
    the shading point. (Not Cycles' Spot: that is the intensity times c times a smoothstep ramp.)"""
    peak = max(intensity)
    ld = bpy.data.lights.new(name, type="POINT")
    ld.energy = POINT_POWER_PER_INTENSITY * peak
    ld.color = [x / peak for x in intensity] if peak > 0 else (1, 1, 1)
    ld.shadow_soft_size = 0.0  # Blender's default is 0.25: a disc (see the docstring)
    if spot is not None:
        direction, inner_deg, outer_deg = spot
        ax = [float(x) for x in direction]
        n = math.sqrt(sum(x * x for x in ax))
        ax = [x / n for x in ax]
        ci, co = math.cos(math.radians(inner_deg)), math.cos(math.radians(outer_deg))
        scale = 1 / max(0.001, ci - co)  # core/light.cpp, the Light constructor
        ld.use_nodes = True
        nt = ld.node_tree
        emission = nt.nodes["Emission"]
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        dot = nt.nodes.new("ShaderNodeVectorMath")
        dot.operation = "DOT_PRODUCT"
        dot.inputs[1].default_value = ax
        nt.links.new(geo.outputs["Normal"], dot.inputs[0])
        ramp = nt.nodes.new("ShaderNodeMath")
        ramp.operation = "MULTIPLY_ADD"
        ramp.use_clamp = True
        ramp.inputs[1].default_value = scale
        ramp.inputs[2].default_value = -co * scale
        nt.links.new(dot.outputs["Value"], ramp.inputs[0])
        square = nt.nodes.new("ShaderNodeMath")
        square.operation = "MULTIPLY"
        nt.links.new(ramp.outputs[0], square.inputs[0])
        nt.links.new(ramp.outputs[0], square.inputs[1])
        nt.links.new(square.outputs[0], emission.inputs["Strength"])
    ob = bpy.data.objects.new(name, ld)
    ob.location = [float(x) for x in position]
    scene.collection.objects.link(ob)
    return ob


def native_spot_light(scene, name, position, intensity, direction, inner_deg, outer_deg):
    """--native-lights only: Cycles' own Spot on the same cone, which is not KHR's falloff."""
    from mathutils import Vector

    peak = max(intensity)
    ld = bpy.data.lights.new(name, type="SPOT")
    ld.energy = POINT_POWER_PER_INTENSITY * peak
    ld.color = [x / peak for x in intensity] if peak > 0 else (1, 1, 1)
    ld.shadow_soft_size = 0.0
    ci, co = math.cos(math.radians(inner_deg)), math.cos(math.radians(outer_deg))
    ld.spot_size = 2 * math.radians(outer_deg)
    ld.spot_blend = (ci - co) / (1 - co)  # Cycles' ramp spans cos outer .. cos inner
    ob = bpy.data.objects.new(name, ld)
    ob.location = [float(x) for x in position]
    ob.rotation_mode = "QUATERNION"
    ob.rotation_quaternion = (-Vector(direction)).to_track_quat("Z", "Y")  # shines along -Z
    scene.collection.objects.link(ob)
    return ob


def sphere_light(scene, name, position, radius, radiance):
    """A sphere light of radiance L (RGB): an icosphere (SPHERE_SUBDIVISIONS) of an Emission
    shader of strength max(L) and colour L / max(L) (Cycles' emission strength is radiance), not
    sampled as a light (material.cycles.sample_as_light off: BSDF and phase-function rays find it,
    next-event estimation does not; with it Cycles 3.4's estimate depends on the order of the
    faces by up to 1 %). Opaque and black like ssslab's sphere light, which ends the paths and
    shadow rays that meet it."""
    import bmesh

    bm = bmesh.new()
    bmesh.ops.create_icosphere(bm, subdivisions=SPHERE_SUBDIVISIONS, radius=float(radius))
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    peak = max(radiance)
    m, nt, out = node_material(name)
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*([x / peak for x in radiance] if peak > 0 else (1, 1, 1)), 1)
    em.inputs["Strength"].default_value = peak
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    m.cycles.sample_as_light = False
    me.materials.append(m)
    ob = bpy.data.objects.new(name, me)
    ob.location = [float(x) for x in position]
    scene.collection.objects.link(ob)
    return ob


def look_at_matrix(pos, target, up):
    from mathutils import Matrix, Vector

    p, t, u = Vector(pos), Vector(target), Vector(up)
    f = (t - p).normalized()
    r = f.cross(u).normalized()
    uu = r.cross(f)
    # Blender cameras look along local -Z with +Y up.
    m = Matrix(((r.x, uu.x, -f.x, p.x), (r.y, uu.y, -f.y, p.y), (r.z, uu.z, -f.z, p.z), (0, 0, 0, 1)))
    return m


def unbiased_settings(scene, width, height, spp, threads, seed):
    """Cycles as an unbiased reference (also scripts/cycles_light_check.py): every bounce limit at
    Cycles' maximum, no clamping, no glossy filter, caustics on, no adaptive sampling, no
    denoising, light threshold 0, a box pixel filter one pixel wide, linear float EXR output."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = width
    r.resolution_y = height
    r.resolution_percentage = 100
    r.film_transparent = False
    r.use_persistent_data = False
    if threads > 0:
        r.threads_mode = "FIXED"
        r.threads = threads
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = spp
    cy.seed = seed
    cy.use_animated_seed = False
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.max_bounces = 1024
    cy.diffuse_bounces = 1024
    cy.glossy_bounces = 1024
    cy.transmission_bounces = 1024
    cy.volume_bounces = 1024
    cy.transparent_max_bounces = 1024
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    cy.light_sampling_threshold = 0.0
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.film_exposure = 1.0
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    s = r.image_settings
    s.file_format = "OPEN_EXR"
    s.color_depth = "32"
    s.color_mode = "RGB"
    s.exr_codec = "ZIP"
    r.use_file_extension = False


def main():
    a = args_after_dashes()
    with open(a.scene_json) as f:
        sc = json.load(f)
    base = os.path.dirname(os.path.abspath(a.scene_json))

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    mats = {}
    for d in sc["materials"]:
        mats[d["name"]] = medium_material(d) if d["type"] == "medium" else diffuse_material(d)
    for s in sc["shapes"]:
        verts, faces = read_obj(os.path.join(base, s["obj"]))
        me = bpy.data.meshes.new(s["name"])
        me.from_pydata(verts, [], faces)
        me.validate()
        me.materials.append(mats[s["material"]])
        ob = bpy.data.objects.new(s["name"], me)
        scene.collection.objects.link(ob)

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0, 0, 0, 1)
    bg.inputs["Strength"].default_value = 1.0
    scene.world = world
    from mathutils import Vector

    for i, l in enumerate(sc["lights"]):
        if l["type"] == "environment":
            bg.inputs["Color"].default_value = (*l["radiance"], 1)
        elif l["type"] == "directional":
            e = l["irradiance"]
            peak = max(e)
            ld = bpy.data.lights.new(f"sun{i}", type="SUN")
            ld.energy = peak
            ld.color = [x / peak for x in e] if peak > 0 else (1, 1, 1)
            ld.angle = 2 * math.radians(l["angular_radius_deg"])
            ob = bpy.data.objects.new(f"sun{i}", ld)
            # A sun shines along its local -Z: point -Z away from the light's direction.
            ob.rotation_mode = "QUATERNION"
            ob.rotation_quaternion = Vector(l["direction"]).to_track_quat("Z", "Y")
            scene.collection.objects.link(ob)
        elif l["type"] == "point":
            point_light(scene, f"point{i}", l["position"], l["intensity"])
        elif l["type"] == "spot" and a.native_lights:
            native_spot_light(scene, f"spot{i}", l["position"], l["intensity"], l["direction"],
                              l["inner_cone_angle_deg"], l["outer_cone_angle_deg"])
        elif l["type"] == "spot":
            point_light(scene, f"spot{i}", l["position"], l["intensity"],
                        spot=(l["direction"], l["inner_cone_angle_deg"], l["outer_cone_angle_deg"]))
        elif l["type"] == "sphere" and a.native_lights:
            ob = point_light(scene, f"sphere{i}", l["position"],
                             [math.pi * l["radius"] ** 2 * x for x in l["radiance"]])
            ob.data.shadow_soft_size = l["radius"]
        elif l["type"] == "sphere":
            sphere_light(scene, f"sphere{i}", l["position"], l["radius"], l["radiance"])
        else:
            fail(f"light {i} ({l['type']}): not a light type this script knows")

    cam = bpy.data.cameras.new("camera")
    cam.lens_unit = "FOV"
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(sc["camera"]["fov_y_deg"])
    cam.clip_start = 1e-3
    cam.clip_end = 1e7
    cob = bpy.data.objects.new("camera", cam)
    c = sc["camera"]
    cob.matrix_world = look_at_matrix(c["position"], c["target"], c["up"])
    scene.collection.objects.link(cob)
    scene.camera = cob

    unbiased_settings(scene, a.width or c["width"], a.height or c["height"], a.spp, a.threads,
                      a.seed)
    r = scene.render
    s = r.image_settings
    if a.passes:
        vl = scene.view_layers[0]
        for p in ("diffuse_direct", "diffuse_indirect", "diffuse_color", "glossy_direct",
                  "glossy_indirect", "glossy_color", "transmission_direct",
                  "transmission_indirect", "transmission_color", "environment"):
            setattr(vl, "use_pass_" + p, True)
        s.file_format = "OPEN_EXR_MULTILAYER"
    else:
        s.file_format = "OPEN_EXR"
    r.filepath = os.path.abspath(a.out_exr)
    start = time.monotonic()
    bpy.ops.render.render(write_still=True)
    seconds = time.monotonic() - start
    print(f"cycles_render.py: wrote {a.out_exr} ({r.resolution_x}x{r.resolution_y}, {a.spp} spp, seed {a.seed})")
    # The render alone (scene sync, BVH build, sampling, writing), without Blender's start-up.
    print(f"cycles_render.py: render_seconds {seconds:.3f}")


if __name__ == "__main__":
    main()
