"""Render the scene of a `clayfit synth` capture in Blender with Cycles, with a
material preset `clayfit export --format blender` wrote (docs/fidelity.md).

usage: blender -b --factory-startup --python-exit-code 1 -P scripts/blender_render.py -- \
           --capture DIR --preset PRESET.py --out OUT.exr [--image N] [--samples S]
           [--set INPUT=VALUE ...] [--seed N] [--diffuse-only R G B]
           [--interpolation Closest|Linear] [--rotation R00,R01,...,R22]

The scene is the capture's, read from its files, not restated here: the
sphere (truth.json: centre, radius), camera N (sparse/0/cameras.txt and
images.txt: PINHOLE intrinsics and pose) and its flash (truth.json: offset in
camera coordinates and radiant intensity I). clayfit's point light of
intensity I (docs/model.md (36)) is a Cycles point light of radius 0 and power
4 pi I: Cycles gives a point light of power P the intensity P / (4 pi) W/sr
(intern/cycles/scene/light.cpp: eval_fac = 1/(4 pi) for a point). The sphere is
exact: one point of a geometry-nodes point cloud, which Cycles intersects as
a true sphere (a mesh's facets and interpolated normals would add their own
error). No ground, black world, direct light only (max_bounces 0): clayfit's
image formation has no inter-reflection (docs/model.md §5.1). The pixel is a
box of 1 px (clayfit synth averages S x S samples over the pixel's square).
Linear float OpenEXR, view transform Standard, exposure 0, gamma 1, no
denoising (Debian's build has no OpenImageDenoise).

Under a map (truth.json's "environment": synth --environment), the flash is
replaced by a world of that map (docs/fidelity.md, "HDRI rows"): an Environment
Texture whose vector is C R^T D for the ray direction D, with R the capture's
rotation (map frame to world) and C scene_compare.CYCLES_FROM_MAP (Cycles'
equirectangular frame against clayfit's, a rotation), so each direction sees the
texel clayfit's lights came from, its negative values (a lossy EXR's ringing)
counted as 0 as clayfit counts them. Interpolation Closest (default: clayfit
holds a texel's radiance constant over its solid angle), world importance
sampling at the map's own resolution. --rotation replaces the capture's
rotation (9 numbers, rows): to show the orientation check fails on a wrong one.

--diffuse-only replaces the preset with a Diffuse BSDF of the fit's albedo
(Lambert in Cycles at roughness 0), which tests the scene, units and pixel
filter alone against `clayfit synth --model M0`.
"""
import argparse
import json
import math
import os
import runpy
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_common as bc  # noqa: E402
import scene_compare as sc  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_render.py")
    p.add_argument("--capture", required=True, help="a clayfit synth output folder")
    p.add_argument("--preset", help="a clayfit export --format blender script")
    p.add_argument("--out", required=True, help="the OpenEXR to write")
    p.add_argument("--image", type=int, default=0, help="which camera (0-based, default 0)")
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--set", action="append", default=[], metavar="INPUT=VALUE",
                   help="after the preset, set this Principled input (a number, or r,g,b): "
                        "to measure another mapping (docs/fidelity.md)")
    p.add_argument("--seed", type=int, default=1, help="Cycles' seed")
    p.add_argument("--diffuse-only", type=float, nargs=3, metavar=("R", "G", "B"),
                   help="a Lambert material of this albedo instead of the preset")
    p.add_argument("--interpolation", default="Closest", choices=["Closest", "Linear"],
                   help="the environment texture's (under a map; default Closest)")
    p.add_argument("--rotation", help="9 numbers (rows): the map's rotation instead of "
                                      "truth.json's")
    a = p.parse_args(argv)
    if not a.preset and not a.diffuse_only:
        p.error("--preset or --diffuse-only is needed")
    return a


def read_colmap(sparse, index):
    """The camera (w, h, fx, fy, cx, cy) and pose (qw, qx, qy, qz, t) of image index."""
    cameras = {}
    with open(os.path.join(sparse, "cameras.txt"), encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = line.split()
            if v[1] != "PINHOLE":
                raise SystemExit(f"blender_render: camera {v[0]} is {v[1]}, not PINHOLE")
            cameras[v[0]] = [int(v[2]), int(v[3])] + [float(x) for x in v[4:8]]
    images = []
    with open(os.path.join(sparse, "images.txt"), encoding="utf-8") as f:
        lines = [l for l in f if not l.startswith("#")]
    for k in range(0, len(lines), 2):
        v = lines[k].split()
        if v:
            images.append(([float(x) for x in v[1:8]], cameras[v[8]]))
    if not 0 <= index < len(images):
        raise SystemExit(f"blender_render: no image {index} (the model has {len(images)})")
    return images[index]


def add_camera(scene, pose, camera):
    import mathutils
    w, h, fx, fy, cx, cy = camera
    if abs(fx - fy) > 1e-9 * fx:
        raise SystemExit(f"blender_render: fx {fx} != fy {fy}: square pixels only")
    r, centre = sc.rotation(pose[:4]), sc.camera_centre(pose[:4], pose[4:7])
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = 36.0
    data.lens = fx * data.sensor_width / w
    size = max(w, h)
    data.shift_x = (0.5 * w - cx) / size
    data.shift_y = (cy - 0.5 * h) / size
    data.clip_start, data.clip_end = 0.01, 1000.0
    cam = bpy.data.objects.new("camera", data)
    # Blender's camera: x right, y up, looking down -z; COLMAP's: x right, y down, z forward
    m = mathutils.Matrix(((r[0][0], -r[1][0], -r[2][0], centre[0]),
                          (r[0][1], -r[1][1], -r[2][1], centre[1]),
                          (r[0][2], -r[1][2], -r[2][2], centre[2]),
                          (0, 0, 0, 1)))
    cam.matrix_world = m
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    return r, centre


def add_flash(scene, position, intensity):
    data = bpy.data.lights.new("flash", "POINT")
    data.energy = 4.0 * math.pi * intensity
    data.color = (1.0, 1.0, 1.0)
    data.shadow_soft_size = 0.0
    light = bpy.data.objects.new("flash", data)
    light.location = position
    scene.collection.objects.link(light)


def make_material(args):
    if args.diffuse_only:
        return bc.lambert_material("clayfit_lambert", args.diffuse_only)
    preset = runpy.run_path(args.preset, run_name="clayfit_preset")
    material = preset["build"]()
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    for assignment in args.set:
        key, _, text = assignment.partition("=")
        values = [float(x) for x in text.split(",")]
        bsdf.inputs[key].default_value = (*values, 1.0) if len(values) == 3 else values[0]
        print(f"blender_render: {key} = {text}")
    return material


def set_render(scene, args):
    bc.set_cycles(scene, args.samples, args.seed, 0)  # direct light only
    c = scene.cycles
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    for name in ("transmission_bounces", "volume_bounces", "transparent_max_bounces"):
        setattr(c, name, 0)
    c.light_sampling_threshold = 0.0
    if hasattr(c, "use_guiding"):
        c.use_guiding = False
    c.film_exposure = 1.0
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.threads_mode = "AUTO"


def environment_world(scene, env, interpolation, rotation_text):
    """The world of the capture's map: Background (strength 1) of an
    Environment Texture looked up at M D, M = CYCLES_FROM_MAP R^T (three dot
    products, so that --rotation can also hand it a mirror, which must fail)."""
    rotation = env["rotation"]
    if rotation_text:
        v = [float(x) for x in rotation_text.split(",")]
        rotation = [v[0:3], v[3:6], v[6:9]]
    m = sc.matmul(sc.CYCLES_FROM_MAP, sc.transpose(rotation))
    world = bpy.data.worlds.new("environment")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    coords = nodes.new("ShaderNodeTexCoord")
    combine = nodes.new("ShaderNodeCombineXYZ")
    for i, axis in enumerate("XYZ"):
        dot = nodes.new("ShaderNodeVectorMath")
        dot.operation = "DOT_PRODUCT"
        dot.inputs[1].default_value = m[i]
        links.new(coords.outputs["Generated"], dot.inputs[0])
        links.new(dot.outputs["Value"], combine.inputs[axis])
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(os.path.abspath(env["path"]), check_existing=False)
    texture.image.colorspace_settings.name = "Non-Color"  # linear radiance, untouched
    texture.interpolation = interpolation
    texture.projection = "EQUIRECTANGULAR"
    links.new(combine.outputs["Vector"], texture.inputs["Vector"])
    # negative values count as 0, as in clayfit (envmap.h): studio.exr's DWA coding leaves
    # 2028 of them around its sources, -0.54 % of its total, 0.58 % of the Lambert sphere
    clamp = nodes.new("ShaderNodeVectorMath")
    clamp.operation = "MAXIMUM"
    clamp.inputs[1].default_value = (0.0, 0.0, 0.0)
    links.new(texture.outputs["Color"], clamp.inputs[0])
    background = nodes["Background"]
    background.inputs["Strength"].default_value = 1.0
    links.new(clamp.outputs["Vector"], background.inputs["Color"])
    world.cycles.sampling_method = "MANUAL"  # importance sampled at the map's resolution
    world.cycles.sample_map_resolution = texture.image.size[0]
    scene.world = world


def main():
    args = parse_args()
    with open(os.path.join(args.capture, "truth.json"), encoding="utf-8") as f:
        truth = json.load(f)
    pose, camera = read_colmap(os.path.join(args.capture, "sparse", "0"), args.image)
    bc.clear_scene()
    scene = bpy.context.scene
    r, centre = add_camera(scene, pose, camera)
    env = sc.truth_environment(args.capture)
    if not env:
        add_flash(scene, *sc.flash(args.capture, {"r": r, "centre": centre}))
    bc.add_exact_sphere(scene, truth["sphere"]["center"], truth["sphere"]["radius"],
                        make_material(args))
    set_render(scene, args)
    if env:
        environment_world(scene, env, args.interpolation, args.rotation)
    scene.render.filepath = os.path.abspath(args.out)
    bpy.ops.render.render(write_still=True)
    if not os.path.exists(scene.render.filepath):
        raise SystemExit(f"blender_render: Blender wrote no {scene.render.filepath}")
    print(f"blender_render: wrote {scene.render.filepath} (Blender {bpy.app.version_string}, "
          f"{args.samples} samples)")


main()
