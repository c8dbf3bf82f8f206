"""Run clayfit's Blender presets in this Blender (3.x: the Principled v1 branch)
and check what they set (docs/fidelity.md, docs/presets.md).

usage: blender -b --factory-startup --python-exit-code 1 -P check_blender_preset.py -- PRESET.py ...

For each preset: build() runs without error and makes a material whose
Principled BSDF holds every value of INPUTS_V1 (to float32) with distribution
GGX; the Blender 4 branch (INPUTS), which this Blender cannot run, compiles
and names only Blender 4 inputs (source/blender/nodes/shader/nodes/
node_shader_bsdf_principled.cc of 4.x; Diffuse Roughness since 4.3).
"""
import ast
import os
import runpy
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from principled_inputs import BLENDER4  # noqa: E402


def close(a, b):
    return abs(a - b) <= 1e-6 * max(1.0, abs(b))


def check(path, failures):
    source = open(path, encoding="utf-8").read()
    tree = ast.parse(source, path)  # the whole script, both branches
    names = {t.id for node in ast.walk(tree) if isinstance(node, ast.Assign)
             for t in node.targets if isinstance(t, ast.Name)}
    for needed in ("INPUTS", "INPUTS_V1", "OPTIONAL", "NAME"):
        if needed not in names:
            failures.append(f"{path}: no {needed}")
    scope = runpy.run_path(path, run_name="clayfit_preset")
    for key in scope["INPUTS"]:
        if key not in BLENDER4:
            failures.append(f"{path}: '{key}' (INPUTS) is not a Blender 4 Principled input")
    if bpy.app.version >= (4, 0, 0):
        failures.append(f"this is Blender {bpy.app.version_string}: the test is for 3.x")
        return
    material = scope["build"]()
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    if bsdf.distribution != "GGX":
        failures.append(f"{path}: distribution {bsdf.distribution}, not GGX")
    for key, value in scope["INPUTS_V1"].items():
        got = bsdf.inputs[key].default_value
        want = list(value) if isinstance(value, tuple) else [value]
        got = list(got) if hasattr(got, "__len__") else [got]
        if len(got) != len(want) or not all(close(g, w) for g, w in zip(got, want)):
            failures.append(f"{path}: {key} is {got}, INPUTS_V1 says {want}")
    print(f"{path}: Blender {bpy.app.version_string}: {len(scope['INPUTS_V1'])} v1 inputs set, "
          f"{len(scope['INPUTS'])} v2 inputs named")


def main():
    paths = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not paths:
        raise SystemExit("usage: ... -- PRESET.py ...")
    failures = []
    for path in paths:
        check(path, failures)
    for f in failures:
        print("FAIL:", f)
    if failures:
        raise SystemExit(1)


main()
