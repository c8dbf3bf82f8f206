"""Render a clay sphere that clayfit did not render: Blender as the camera (issue 19, item 2;
docs/roundtrip.md).

usage: blender -b --factory-startup --python-exit-code 1 -P scripts/blender_scene.py -- \
           --out DIR [--views N] [--size WxH] [--samples S] [--light flash|hdri]
           [--hdri MAP.exr] [--base-color R,G,B] [--roughness R] [--specular S]
           [--arc DEG] [--seed N] [--bounces N] [--material principled|lambert]

The scene: a sphere of radius 1 (an exact sphere: one point of a geometry-nodes
point cloud, as scripts/blender_render.py) resting on a textured ground at z = 0,
centre (0, 0, 1), inside a textured cylindrical backdrop (with the flash; under an
HDRI the map is the backdrop), so that COLMAP finds features. Its material is one
Principled BSDF (Blender 3.x, v1) with the given Base Color, Roughness and
Specular, single-scatter GGX, everything else 0.

N cameras orbit the sphere at distance 5 over an arc of --arc degrees,
alternately 25 and 35 degrees up, all looking at the sphere's centre, one
PINHOLE camera (f = 1.2 x width, principal point at the centre).

Lights (--light):
- flash: a point light of radius 0 that moves with the camera, at --flash-offset
  in COLMAP camera coordinates (x right, y down, z forward; Blender units), of
  radiant intensity I (W/sr): Cycles power 4 pi I. The world is black.
- hdri: the world is the equirectangular map at --hdri-strength, no other light.
--material lambert replaces the Principled BSDF with a Diffuse BSDF (roughness 0), a control
that clayfit's M0 describes exactly.

Each view is rendered once and written twice: DIR/png8/NNN.png, 8-bit sRGB through
the "Standard" view transform, and DIR/linear/NNN.exr, linear 32-bit float. Full
light transport (shadows, inter-reflection from the ground), Cycles on the CPU,
no denoising (Debian's build has no OpenImageDenoise). DIR/scene.json holds the
truth: the sphere, the Principled values, the light, each camera's intrinsics and
COLMAP-convention pose (world to camera), the render settings and times.
"""
import argparse
import json
import math
import os
import sys
import time

import bpy
import mathutils

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_common as bc  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_scene.py")
    p.add_argument("--out", required=True)
    p.add_argument("--views", type=int, default=8)
    p.add_argument("--size", default="320x240")
    p.add_argument("--samples", type=int, default=32)
    p.add_argument("--light", choices=("flash", "hdri"), default="flash")
    p.add_argument("--hdri", help="an equirectangular map (--light hdri)")
    p.add_argument("--hdri-strength", type=float, default=1.0)
    p.add_argument("--base-color", default="0.6,0.35,0.2")
    p.add_argument("--roughness", type=float, default=0.35)
    p.add_argument("--specular", type=float, default=0.5)
    p.add_argument("--flash-offset", default="0.3,-0.3,0", help="COLMAP camera coordinates")
    p.add_argument("--flash-intensity", type=float, default=40.0, help="W/sr")
    p.add_argument("--arc", type=float, default=120.0, help="degrees of the orbit")
    p.add_argument("--distance", type=float, default=5.0)
    p.add_argument("--bounces", type=int, default=4)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--material", choices=("principled", "lambert"), default="principled",
                   help="lambert: a Diffuse BSDF of roughness 0 and colour --base-color, the "
                        "control that M0 describes exactly")
    a = p.parse_args(argv)
    a.width, a.height = (int(x) for x in a.size.lower().split("x"))
    a.base_color = [float(x) for x in a.base_color.split(",")]
    a.flash_offset = [float(x) for x in a.flash_offset.split(",")]
    if a.light == "hdri" and not a.hdri:
        p.error("--light hdri needs --hdri")
    if a.views < 2:
        p.error("--views must be at least 2")
    return a


SPHERE_CENTRE = (0.0, 0.0, 1.0)
SPHERE_RADIUS = 1.0


def principled(args):
    if args.material == "lambert":
        return bc.lambert_material("lambert_truth", args.base_color)
    m = bpy.data.materials.new("principled_truth")
    m.use_nodes = True
    nodes = m.node_tree.nodes
    bsdf = next(n for n in nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.distribution = "GGX"  # single scattering, as the model's lobe
    bsdf.subsurface_method = "BURLEY"
    bsdf.inputs["Base Color"].default_value = (*args.base_color, 1.0)
    bsdf.inputs["Roughness"].default_value = args.roughness
    bsdf.inputs["Specular"].default_value = args.specular
    for name in ("Metallic", "Subsurface", "Specular Tint", "Anisotropic", "Sheen",
                 "Clearcoat", "Transmission"):
        bsdf.inputs[name].default_value = 0.0
    bsdf.inputs["IOR"].default_value = (1 + math.sqrt(0.08 * args.specular)) / (
        1 - math.sqrt(0.08 * args.specular))
    return m


def textured(name, colour_a, colour_b, scale, seed):
    """A diffuse material of noise mixed with Voronoi cells: corners for SIFT."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nodes, links = nt.nodes, nt.links
    for n in list(nodes):
        if n.type != "OUTPUT_MATERIAL":
            nodes.remove(n)
    coords = nodes.new("ShaderNodeTexCoord")
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scale
    noise.inputs["Detail"].default_value = 4.0
    noise.inputs["W"].default_value = seed
    noise.noise_dimensions = "4D"
    voronoi = nodes.new("ShaderNodeTexVoronoi")
    voronoi.inputs["Scale"].default_value = scale * 0.5
    ramp = nodes.new("ShaderNodeValToRGB")  # hard-edged blobs: high contrast at any scale
    ramp.color_ramp.elements[0].position, ramp.color_ramp.elements[1].position = 0.38, 0.62
    ramp.color_ramp.elements[0].color = (*colour_a, 1.0)
    ramp.color_ramp.elements[1].color = (*colour_b, 1.0)
    mix = nodes.new("ShaderNodeMixRGB")
    mix.blend_type = "MULTIPLY"
    mix.inputs["Fac"].default_value = 0.5
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    links.new(coords.outputs["Object"], noise.inputs["Vector"])
    links.new(coords.outputs["Object"], voronoi.inputs["Vector"])
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], mix.inputs["Color1"])
    links.new(voronoi.outputs["Color"], mix.inputs["Color2"])
    links.new(mix.outputs["Color"], diffuse.inputs["Color"])
    links.new(diffuse.outputs["BSDF"], out.inputs["Surface"])
    return m


def add_mesh(scene, name, verts, faces, material):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)


def add_set(scene, seed, backdrop=True):
    """The ground (a 100 x 100 square at z = 0: from the sphere its edge is 1.1 degrees below the
    horizon, so that it hides the map's lower half) and the backdrop (a cylinder of radius 7.5)."""
    g = 50.0
    add_mesh(scene, "ground", [(-g, -g, 0), (g, -g, 0), (g, g, 0), (-g, g, 0)], [(0, 1, 2, 3)],
             textured("ground", (0.05, 0.05, 0.05), (0.8, 0.8, 0.8), 3.0, seed))
    if not backdrop:
        return
    n, radius, height = 48, 7.5, 8.0
    verts, faces = [], []
    for k in range(n):
        a = 2 * math.pi * k / n
        verts += [(radius * math.cos(a), radius * math.sin(a), 0.0),
                  (radius * math.cos(a), radius * math.sin(a), height)]
    for k in range(n):
        j = (k + 1) % n
        faces.append((2 * k, 2 * k + 1, 2 * j + 1, 2 * j))
    add_mesh(scene, "backdrop", verts, faces,
             textured("backdrop", (0.05, 0.05, 0.05), (0.9, 0.9, 0.9), 1.5, seed + 7))


def orbit(args):
    """Camera centres: an arc centred on -y at distance d, alternately 25 and 35 degrees up."""
    out = []
    for k in range(args.views):
        azimuth = math.radians(-90.0 - args.arc / 2 + args.arc * k / (args.views - 1))
        elevation = math.radians(25.0 if k % 2 == 0 else 35.0)
        d = args.distance
        out.append((SPHERE_CENTRE[0] + d * math.cos(elevation) * math.cos(azimuth),
                    SPHERE_CENTRE[1] + d * math.cos(elevation) * math.sin(azimuth),
                    SPHERE_CENTRE[2] + d * math.sin(elevation)))
    return out


def look_at(centre):
    """COLMAP world-to-camera rotation rows (x right, y down, z forward) looking at the sphere."""
    z = mathutils.Vector(SPHERE_CENTRE) - mathutils.Vector(centre)
    z.normalize()
    x = z.cross(mathutils.Vector((0, 0, 1)))
    x.normalize()
    y = z.cross(x)
    return [list(x), list(y), list(z)]


def add_camera(scene, args):
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = 36.0
    data.lens = 1.2 * data.sensor_width
    data.clip_start, data.clip_end = 0.01, 1000.0
    cam = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.height
    scene.render.resolution_percentage = 100
    return cam


def place_camera(cam, r, centre):
    # Blender's camera: x right, y up, looking down -z; COLMAP's: x right, y down, z forward
    cam.matrix_world = mathutils.Matrix(((r[0][0], -r[1][0], -r[2][0], centre[0]),
                                         (r[0][1], -r[1][1], -r[2][1], centre[1]),
                                         (r[0][2], -r[1][2], -r[2][2], centre[2]),
                                         (0, 0, 0, 1)))


def add_flash(scene, args):
    data = bpy.data.lights.new("flash", "POINT")
    data.energy = 4.0 * math.pi * args.flash_intensity  # Cycles: I = P / (4 pi)
    data.shadow_soft_size = 0.0
    light = bpy.data.objects.new("flash", data)
    scene.collection.objects.link(light)
    return light


def set_world(scene, args):
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    background = nodes["Background"]
    if args.light == "flash":
        background.inputs["Strength"].default_value = 0.0
        background.inputs["Color"].default_value = (0, 0, 0, 1)
    else:
        env = nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.load(os.path.abspath(args.hdri))
        env.image.colorspace_settings.name = "Linear"
        links.new(env.outputs["Color"], background.inputs["Color"])
        background.inputs["Strength"].default_value = args.hdri_strength
    scene.world = world


def set_render(scene, args):
    bc.set_cycles(scene, args.samples, args.seed, args.bounces)
    scene.display_settings.display_device = "sRGB"


def save(scene, path, fmt):
    s = scene.render.image_settings
    s.color_mode = "RGB"
    if fmt == "png8":
        s.file_format, s.color_depth, s.compression = "PNG", "8", 15
    else:
        s.file_format, s.color_depth, s.exr_codec = "OPEN_EXR", "32", "ZIP"
    bpy.data.images["Render Result"].save_render(path, scene=scene)


def quaternion(r):
    """(qw, qx, qy, qz) of a rotation matrix (rows), as COLMAP writes it."""
    q = mathutils.Matrix(r).to_quaternion()
    return [q.w, q.x, q.y, q.z]


def main():
    args = parse_args()
    for sub in ("png8", "linear"):
        os.makedirs(os.path.join(args.out, sub), exist_ok=True)
    bc.clear_scene()
    scene = bpy.context.scene
    bc.add_exact_sphere(scene, SPHERE_CENTRE, SPHERE_RADIUS, principled(args))
    add_set(scene, args.seed, backdrop=args.light == "flash")  # the map is the hdri's backdrop
    cam = add_camera(scene, args)
    flash = add_flash(scene, args) if args.light == "flash" else None
    set_world(scene, args)
    set_render(scene, args)
    f = 1.2 * args.width
    views, seconds = [], []
    for k, centre in enumerate(orbit(args)):
        r = look_at(centre)
        place_camera(cam, r, centre)
        if flash:
            o = args.flash_offset
            flash.location = [centre[i] + sum(r[j][i] * o[j] for j in range(3)) for i in range(3)]
        scene.cycles.seed = args.seed + k
        start = time.time()
        bpy.ops.render.render()
        seconds.append(time.time() - start)
        name = f"{k:03d}"
        save(scene, os.path.abspath(os.path.join(args.out, "png8", name + ".png")), "png8")
        save(scene, os.path.abspath(os.path.join(args.out, "linear", name + ".exr")), "exr")
        t = [-sum(r[i][j] * centre[j] for j in range(3)) for i in range(3)]
        views.append({"name": name, "qvec": quaternion(r), "tvec": t, "centre": list(centre)})
        print(f"blender_scene: view {name} in {seconds[-1]:.1f} s", flush=True)
    truth = {
        "blender": bpy.app.version_string,
        "sphere": {"center": list(SPHERE_CENTRE), "radius": SPHERE_RADIUS},
        "material": args.material,
        "principled": {"version": "v1", "distribution": "GGX", "base_color": args.base_color,
                       "roughness": args.roughness, "specular": args.specular,
                       "f0": 0.08 * args.specular},
        "light": ({"type": "flash", "offset": args.flash_offset,
                   "intensity": args.flash_intensity} if args.light == "flash" else
                  {"type": "hdri", "file": os.path.abspath(args.hdri),
                   "strength": args.hdri_strength,
                   # Cycles: u = (atan2(y, x) - pi) / (-2 pi), v = 1 - acos(z) / pi (v up):
                   # the map's direction (clayfit, envmap.h) m = (x, z, -y)
                   "map_to_world": [[1, 0, 0], [0, 0, -1], [0, 1, 0]]}),
        "camera": {"model": "PINHOLE", "width": args.width, "height": args.height,
                   "params": [f, f, args.width / 2, args.height / 2]},
        "views": views,
        "render": {"samples": args.samples, "bounces": args.bounces, "seed": args.seed,
                   "seconds": seconds},
    }
    with open(os.path.join(args.out, "scene.json"), "w", encoding="utf-8") as fh:
        json.dump(truth, fh, indent=1)
    print(f"blender_scene: {len(views)} views in {sum(seconds):.1f} s", flush=True)


main()
