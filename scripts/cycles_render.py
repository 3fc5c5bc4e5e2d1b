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
- camera: pinhole, vertical field of view, the scene's up vector; box pixel filter one pixel
  wide (ssslab samples the pixel uniformly);
- every bounce limit at Cycles' maximum (1024), no clamping, no glossy filter, no adaptive
  sampling, no denoising, light threshold 0; linear EXR output (no view transform).

Point and sphere lights are refused: Cycles 3.4 samples a point light with a radius as a disc
facing the shading point, not a sphere, and its watt-to-radiance conventions for point lights
are not what ssslab's scene units say; comparing them would test the conversion, not transport.
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


def look_at_matrix(pos, target, up):
    from mathutils import Matrix, Vector

    p, t, u = Vector(pos), Vector(target), Vector(up)
    f = (t - p).normalized()
    r = f.cross(u).normalized()
    uu = r.cross(f)
    # Blender cameras look along local -Z with +Y up.
    m = Matrix(((r.x, uu.x, -f.x, p.x), (r.y, uu.y, -f.y, p.y), (r.z, uu.z, -f.z, p.z), (0, 0, 0, 1)))
    return m


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
        else:
            fail(f"light {i} ({l['type']}): only directional and environment lights are exported")

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

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x = a.width or c["width"]
    r.resolution_y = a.height or c["height"]
    r.resolution_percentage = 100
    r.film_transparent = False
    r.use_persistent_data = False
    if a.threads > 0:
        r.threads_mode = "FIXED"
        r.threads = a.threads
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = a.spp
    cy.seed = a.seed
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
    if a.passes:
        vl = scene.view_layers[0]
        for p in ("diffuse_direct", "diffuse_indirect", "diffuse_color", "glossy_direct",
                  "glossy_indirect", "glossy_color", "transmission_direct",
                  "transmission_indirect", "transmission_color", "environment"):
            setattr(vl, "use_pass_" + p, True)
        s.file_format = "OPEN_EXR_MULTILAYER"
    else:
        s.file_format = "OPEN_EXR"
    s.color_depth = "32"
    s.color_mode = "RGB"
    s.exr_codec = "ZIP"
    r.filepath = os.path.abspath(a.out_exr)
    r.use_file_extension = False
    start = time.monotonic()
    bpy.ops.render.render(write_still=True)
    seconds = time.monotonic() - start
    print(f"cycles_render.py: wrote {a.out_exr} ({r.resolution_x}x{r.resolution_y}, {a.spp} spp, seed {a.seed})")
    # The render alone (scene sync, BVH build, sampling, writing), without Blender's start-up.
    print(f"cycles_render.py: render_seconds {seconds:.3f}")


main()
