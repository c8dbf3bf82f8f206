"""The Principled BSDF's input names, Blender 4 (v2) and 3.x (v1): the
Blender preset's tests check the script's names against them
(check_export.py, and check_blender_preset.py inside Blender)."""

# Blender 4 Principled BSDF inputs: source/blender/nodes/shader/nodes/
# node_shader_bsdf_principled.cc (Diffuse Roughness since 4.3)
BLENDER4 = {
    "Base Color", "Metallic", "Roughness", "IOR", "Alpha", "Normal", "Diffuse Roughness",
    "Subsurface Weight", "Subsurface Radius", "Subsurface Scale", "Subsurface IOR",
    "Subsurface Anisotropy", "Specular IOR Level", "Specular Tint", "Anisotropic",
    "Anisotropic Rotation", "Tangent", "Transmission Weight", "Coat Weight", "Coat Roughness",
    "Coat IOR", "Coat Tint", "Coat Normal", "Sheen Weight", "Sheen Roughness", "Sheen Tint",
    "Emission Color", "Emission Strength", "Thin Film Thickness", "Thin Film IOR",
}
# Blender 3.x (Principled v1) inputs, INPUTS_V1 (the same file of 3.4)
BLENDER_V1 = {
    "Base Color", "Subsurface", "Subsurface Radius", "Subsurface Color", "Subsurface IOR",
    "Subsurface Anisotropy", "Metallic", "Specular", "Specular Tint", "Roughness",
    "Anisotropic", "Anisotropic Rotation", "Sheen", "Sheen Tint", "Clearcoat",
    "Clearcoat Roughness", "IOR", "Transmission", "Transmission Roughness", "Emission",
    "Emission Strength", "Alpha", "Normal", "Clearcoat Normal", "Tangent",
}
