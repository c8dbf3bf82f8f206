"""What the Blender scripts share, run inside Blender 3.4's Python
(blender_render.py for the fidelity table, blender_scene.py for the round trip):
the default scene cleared, a Lambert material, the exact sphere, and Cycles set
for a measurement (CPU, no adaptive sampling, no denoising, no clamping, no
glossy blur or caustics, the "Standard" view with no look, exposure or gamma).
"""
import bpy


def clear_scene():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    for collection in (bpy.data.meshes, bpy.data.lights, bpy.data.cameras, bpy.data.materials):
        for block in list(collection):
            collection.remove(block)


def lambert_material(name, colour):
    """A Diffuse BSDF of roughness 0 (Lambert in Cycles) and the given RGB colour."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    for n in list(nodes):
        if n.type != "OUTPUT_MATERIAL":
            nodes.remove(n)
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*colour, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    output = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    material.node_tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    return material


def add_exact_sphere(scene, centre, radius, material):
    """One vertex turned into a point of radius R by geometry nodes: an exact
    sphere, which Cycles intersects as such (a mesh's facets and interpolated
    normals would add their own error)."""
    mesh = bpy.data.meshes.new("sphere_point")
    mesh.from_pydata([tuple(centre)], [], [])
    obj = bpy.data.objects.new("sphere", mesh)
    scene.collection.objects.link(obj)
    tree = bpy.data.node_groups.new("clayfit_sphere", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = tree.nodes, tree.links
    group_in, group_out = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    to_points = nodes.new("GeometryNodeMeshToPoints")
    to_points.inputs["Radius"].default_value = radius
    set_material = nodes.new("GeometryNodeSetMaterial")
    set_material.inputs["Material"].default_value = material
    links.new(group_in.outputs["Geometry"], to_points.inputs["Mesh"])
    links.new(to_points.outputs["Points"], set_material.inputs["Geometry"])
    links.new(set_material.outputs["Geometry"], group_out.inputs["Geometry"])
    obj.modifiers.new("clayfit_sphere", "NODES").node_group = tree


def set_cycles(scene, samples, seed, bounces):
    """Cycles on the CPU for a measurement, with `bounces` diffuse and glossy
    bounces (0: direct light only)."""
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False  # (Debian's build has no OpenImageDenoise)
    c.seed = seed
    c.max_bounces = bounces
    c.diffuse_bounces = c.glossy_bounces = bounces
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = c.caustics_refractive = False
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
