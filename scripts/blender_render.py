"""Render the scene of a `clayfit synth` capture in Blender with Cycles, with a
material preset `clayfit export --format blender` wrote (docs/fidelity.md).

usage: blender -b --factory-startup --python-exit-code 1 -P scripts/blender_render.py -- \
           --capture DIR --preset PRESET.py --out OUT.exr [--image N] [--samples S]
           [--set INPUT=VALUE ...] [--seed N] [--diffuse-only R G B]

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


def rotation(q):
    """World-to-camera rotation (row-major 3x3) of a unit quaternion (qw, qx, qy, qz)."""
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def clear_scene():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    for collection in (bpy.data.meshes, bpy.data.lights, bpy.data.cameras, bpy.data.materials):
        for block in list(collection):
            collection.remove(block)


def add_camera(scene, pose, camera):
    import mathutils
    w, h, fx, fy, cx, cy = camera
    if abs(fx - fy) > 1e-9 * fx:
        raise SystemExit(f"blender_render: fx {fx} != fy {fy}: square pixels only")
    r = rotation(pose[:4])
    t = pose[4:7]
    centre = [-sum(r[i][k] * t[i] for i in range(3)) for k in range(3)]
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


def add_flash(scene, r, centre, flash):
    offset, intensity = flash["offset"], flash["intensity"]
    position = [centre[k] + sum(r[i][k] * offset[i] for i in range(3)) for k in range(3)]
    data = bpy.data.lights.new("flash", "POINT")
    data.energy = 4.0 * math.pi * intensity
    data.color = (1.0, 1.0, 1.0)
    data.shadow_soft_size = 0.0
    light = bpy.data.objects.new("flash", data)
    light.location = position
    scene.collection.objects.link(light)


def add_sphere(scene, sphere, material):
    """One vertex turned into a point of radius R by geometry nodes: an exact sphere."""
    mesh = bpy.data.meshes.new("sphere_point")
    mesh.from_pydata([tuple(sphere["center"])], [], [])
    obj = bpy.data.objects.new("sphere", mesh)
    scene.collection.objects.link(obj)
    tree = bpy.data.node_groups.new("clayfit_sphere", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = tree.nodes, tree.links
    group_in = nodes.new("NodeGroupInput")
    group_out = nodes.new("NodeGroupOutput")
    to_points = nodes.new("GeometryNodeMeshToPoints")
    to_points.inputs["Radius"].default_value = sphere["radius"]
    set_material = nodes.new("GeometryNodeSetMaterial")
    set_material.inputs["Material"].default_value = material
    links.new(group_in.outputs["Geometry"], to_points.inputs["Mesh"])
    links.new(to_points.outputs["Points"], set_material.inputs["Geometry"])
    links.new(set_material.outputs["Geometry"], group_out.inputs["Geometry"])
    modifier = obj.modifiers.new("clayfit_sphere", "NODES")
    modifier.node_group = tree


def make_material(args):
    if args.diffuse_only:
        material = bpy.data.materials.new("clayfit_lambert")
        material.use_nodes = True
        nodes = material.node_tree.nodes
        for n in list(nodes):
            if n.type != "OUTPUT_MATERIAL":
                nodes.remove(n)
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (*args.diffuse_only, 1.0)
        diffuse.inputs["Roughness"].default_value = 0.0
        output = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
        material.node_tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
        return material
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
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = args.samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = args.seed
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.max_bounces = 0  # direct light only
    for name in ("diffuse_bounces", "glossy_bounces", "transmission_bounces",
                 "volume_bounces", "transparent_max_bounces"):
        setattr(c, name, 0)
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = c.caustics_refractive = False
    if hasattr(c, "use_guiding"):
        c.use_guiding = False
    c.film_exposure = 1.0
    scene.render.film_transparent = False
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    scene.world = world
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.render.threads_mode = "AUTO"


def main():
    args = parse_args()
    with open(os.path.join(args.capture, "truth.json"), encoding="utf-8") as f:
        truth = json.load(f)
    pose, camera = read_colmap(os.path.join(args.capture, "sparse", "0"), args.image)
    clear_scene()
    scene = bpy.context.scene
    r, centre = add_camera(scene, pose, camera)
    add_flash(scene, r, centre, truth["flash"])
    add_sphere(scene, truth["sphere"], make_material(args))
    set_render(scene, args)
    scene.render.filepath = os.path.abspath(args.out)
    bpy.ops.render.render(write_still=True)
    if not os.path.exists(scene.render.filepath):
        raise SystemExit(f"blender_render: Blender wrote no {scene.render.filepath}")
    print(f"blender_render: wrote {scene.render.filepath} (Blender {bpy.app.version_string}, "
          f"{args.samples} samples)")


main()
