#!/usr/bin/env python3
"""Export one fit.json to one format with `clayfit export` and validate the
file with an independent tool or schema:

  json          data_schema/preset.schema.json (python3-jsonschema), and the
                round trip: `clayfit eval --preset` equals `clayfit eval --model
                M --param ...` with the fit's parameters, to the last bit (a
                tailed model's tail included: the json preset is exact)
  every other format (GGX only): one note "GGX approximation: N % RMS over the
                lobe" per tailed lobe of M2T / M4T, none for the others; at
                tail 2 the exact note with 0 %
  mtlx, mtlx-openpbr, mitsuba
                xmllint --noout, then every node, plugin and input name checked
                against the standard definitions listed below
  gltf          the Khronos glTF validator (npm gltf-validator): no errors
  blender       python3 -m py_compile, and the input names checked

Exit 77 (skipped) when a tool is absent.

With --same-values-as TWIN.json (not json): the file writes the same values
as TWIN's export (a tailed fit at tail 2 and its GGX twin).

usage: check_export.py CLAYFIT FIT.json FORMAT OUT [--schema DIR] [--node-modules DIR]
                       [--same-values-as FIT]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import re
import xml.etree.ElementTree as ET

from principled_inputs import BLENDER4, BLENDER_V1

SKIP = 77

# MaterialX 1.38/1.39 libraries/bxdf/standard_surface.mtlx,
# ND_standard_surface_surfaceshader_100 (github.com/AcademySoftwareFoundation/MaterialX)
STANDARD_SURFACE = {
    "base": "float", "base_color": "color3", "diffuse_roughness": "float", "metalness": "float",
    "specular": "float", "specular_color": "color3", "specular_roughness": "float",
    "specular_IOR": "float", "specular_anisotropy": "float", "specular_rotation": "float",
    "transmission": "float", "transmission_color": "color3", "transmission_depth": "float",
    "transmission_scatter": "color3", "transmission_scatter_anisotropy": "float",
    "transmission_dispersion": "float", "transmission_extra_roughness": "float",
    "subsurface": "float", "subsurface_color": "color3", "subsurface_radius": "color3",
    "subsurface_scale": "float", "subsurface_anisotropy": "float", "sheen": "float",
    "sheen_color": "color3", "sheen_roughness": "float", "coat": "float", "coat_color": "color3",
    "coat_roughness": "float", "coat_anisotropy": "float", "coat_rotation": "float",
    "coat_IOR": "float", "coat_normal": "vector3", "coat_affect_color": "float",
    "coat_affect_roughness": "float", "thin_film_thickness": "float", "thin_film_IOR": "float",
    "emission": "float", "emission_color": "color3", "opacity": "color3",
    "thin_walled": "boolean", "normal": "vector3", "tangent": "vector3",
}
# MaterialX 1.39 libraries/bxdf/open_pbr_surface.mtlx, ND_open_pbr_surface_surfaceshader
OPEN_PBR_SURFACE = {
    "base_weight": "float", "base_color": "color3", "base_diffuse_roughness": "float",
    "base_metalness": "float", "specular_weight": "float", "specular_color": "color3",
    "specular_roughness": "float", "specular_ior": "float",
    "specular_roughness_anisotropy": "float", "transmission_weight": "float",
    "transmission_color": "color3", "transmission_depth": "float",
    "transmission_scatter": "color3", "transmission_scatter_anisotropy": "float",
    "transmission_dispersion_scale": "float", "transmission_dispersion_abbe_number": "float",
    "subsurface_weight": "float", "subsurface_color": "color3", "subsurface_radius": "float",
    "subsurface_radius_scale": "color3", "subsurface_scatter_anisotropy": "float",
    "fuzz_weight": "float", "fuzz_color": "color3", "fuzz_roughness": "float",
    "coat_weight": "float", "coat_color": "color3", "coat_roughness": "float",
    "coat_roughness_anisotropy": "float", "coat_ior": "float", "coat_darkening": "float",
    "thin_film_weight": "float", "thin_film_thickness": "float", "thin_film_ior": "float",
    "emission_luminance": "float", "emission_color": "color3", "geometry_opacity": "float",
    "geometry_thin_walled": "boolean", "geometry_normal": "vector3",
    "geometry_coat_normal": "vector3", "geometry_tangent": "vector3",
    "geometry_coat_tangent": "vector3",
}
# Mitsuba 3 plugin reference, "BSDFs" (mitsuba.readthedocs.io): parameters
# and their types
MITSUBA = {
    "diffuse": {"reflectance": "rgb"},
    "roughplastic": {"distribution": "string", "alpha": "float", "int_ior": "float",
                     "ext_ior": "float", "specular_reflectance": "rgb",
                     "diffuse_reflectance": "rgb", "nonlinear": "boolean",
                     "sample_visible": "boolean"},
    "principled": {"base_color": "rgb", "roughness": "float", "anisotropic": "float",
                   "metallic": "float", "spec_trans": "float", "eta": "float",
                   "specular": "float", "spec_tint": "float", "sheen": "float",
                   "sheen_tint": "float", "flatness": "float", "clearcoat": "float",
                   "clearcoat_gloss": "float"},
}
DIRECTIONS = [("0,0,1", "0,0,1"), ("0.5,0,0.866", "-0.342,0,0.94"), ("0.3,0.2,1", "-0.2,0.4,1"),
              ("0.9,0.1,0.3", "0.1,-0.8,0.5"), ("0.2,0,1", "-0.2,0,1")]


def run(command):
    return subprocess.run(command, capture_output=True, text=True, timeout=300)


def check_xml(path, failures):
    if not shutil.which("xmllint"):
        print("SKIP: xmllint is not installed (Debian: libxml2-utils)")
        sys.exit(SKIP)
    result = run(["xmllint", "--noout", path])
    if result.returncode != 0:
        failures.append(f"xmllint: {result.stderr.strip()}")
        return None
    return ET.parse(path).getroot()


def check_mtlx(path, openpbr, failures):
    root = check_xml(path, failures)
    if root is None:
        return
    version = "1.39" if openpbr else "1.38"
    if root.tag != "materialx" or root.get("version") != version:
        failures.append(f"root <{root.tag} version={root.get('version')}>, expected materialx {version}")
    node, table = ("open_pbr_surface", OPEN_PBR_SURFACE) if openpbr else ("standard_surface",
                                                                         STANDARD_SURFACE)
    shaders = root.findall(node)
    materials = root.findall("surfacematerial")
    if len(shaders) != 1 or len(materials) != 1 or len(root) != 2:
        failures.append(f"expected one {node} and one surfacematerial, got {[c.tag for c in root]}")
        return
    names = set()
    for element in shaders[0]:
        name, kind = element.get("name"), element.get("type")
        if element.tag != "input" or name not in table or table[name] != kind:
            failures.append(f"{node}: <{element.tag} name={name} type={kind}> is not in the nodedef")
        if name in names:
            failures.append(f"{node}: input {name} twice")
        names.add(name)
        values = [float(x) for x in element.get("value").split(",")]
        if len(values) != (3 if kind == "color3" else 1):
            failures.append(f"{node}.{name}: {len(values)} numbers for {kind}")
    inputs = list(materials[0])
    if [(i.get("name"), i.get("type"), i.get("nodename")) for i in inputs] != [
            ("surfaceshader", "surfaceshader", shaders[0].get("name"))]:
        failures.append("surfacematerial does not connect the shader")
    print(f"{node}: {len(names)} inputs, all in the nodedef: {sorted(names)}")


def check_mitsuba(path, failures):
    root = check_xml(path, failures)
    if root is None:
        return
    if root.tag != "scene" or root.get("version") != "3.0.0":
        failures.append("root is not <scene version=\"3.0.0\">")
    bsdfs = root.findall("bsdf")
    if len(bsdfs) != 1:
        failures.append("expected one <bsdf>")
        return
    plugin = bsdfs[0].get("type")
    if plugin not in MITSUBA:
        failures.append(f"unknown plugin {plugin}")
        return
    for element in bsdfs[0]:
        name = element.get("name")
        if MITSUBA[plugin].get(name) != element.tag:
            failures.append(f"{plugin}: <{element.tag} name={name}> is not a parameter")
    print(f"mitsuba {plugin}: {[e.get('name') for e in bsdfs[0]]}")


def check_blender(path, failures):
    result = run([sys.executable, "-m", "py_compile", path])
    if result.returncode != 0:
        failures.append(f"py_compile: {result.stderr.strip()}")
        return
    scope = {}
    source = open(path, encoding="utf-8").read().replace("import bpy", "bpy = None")
    exec(compile(source, path, "exec"), scope)  # noqa: S102 (our own output; bpy stubbed)
    for name in scope["INPUTS"]:
        if name not in BLENDER4:
            failures.append(f"'{name}' is not a Principled BSDF input")
    for name in scope["INPUTS_V1"]:
        if name not in BLENDER_V1:
            failures.append(f"'{name}' is not a Blender 3.x Principled BSDF input")
    print(f"blender inputs: {list(scope['INPUTS'])}; 3.x: {list(scope['INPUTS_V1'])}")


def node_modules(arg):
    candidates = [arg, os.environ.get("CLAYFIT_NODE_MODULES")]
    if shutil.which("npm"):
        result = run(["npm", "root", "-g"])
        if result.returncode == 0:
            candidates.append(result.stdout.strip())
    for c in candidates:
        if c and os.path.isdir(os.path.join(c, "gltf-validator")):
            return c
    return None


def check_gltf(path, modules, failures):
    here = os.path.dirname(os.path.abspath(__file__))
    found = node_modules(modules)
    if not shutil.which("node") or not found:
        print("SKIP: node or the npm package gltf-validator is not installed "
              "(bash scripts/install-deps.sh installs them)")
        sys.exit(SKIP)
    env = dict(os.environ, NODE_PATH=found)
    result = subprocess.run(["node", os.path.join(here, "gltf_validate.js"), path],
                            capture_output=True, text=True, env=env, timeout=300)
    print(result.stdout[-3000:])
    if result.returncode != 0:
        failures.append(f"gltf-validator: errors (exit {result.returncode}) {result.stderr[-500:]}")
        return
    report = json.loads(result.stdout)
    issues = report["issues"]
    print(f"gltf-validator {report['validator']}: {issues['numErrors']} errors, "
          f"{issues['numWarnings']} warnings, {issues['numInfos']} infos")
    if issues["numWarnings"]:
        failures.append("gltf-validator: warnings")
    doc = json.load(open(path, encoding="utf-8"))
    if "clayfit" not in doc["asset"].get("extras", {}):
        failures.append("no mapping notes in asset.extras.clayfit")


def check_json(clayfit, fit_path, path, schema_dir, failures):
    import jsonschema
    doc = json.load(open(path, encoding="utf-8"))
    schema = json.load(open(os.path.join(schema_dir, "preset.schema.json"), encoding="utf-8"))
    for error in jsonschema.Draft202012Validator(schema).iter_errors(doc):
        failures.append(f"schema: {'/'.join(map(str, error.path))}: {error.message}")
    fit = json.load(open(fit_path, encoding="utf-8"))
    args = []
    for name, p in fit["params"].items():
        v = p["value"]
        text = ",".join(repr(float(x)) for x in v) if isinstance(v, list) else repr(float(v))
        args += ["--param", f"{name}={text}"]
    worst = 0.0
    for light, view in DIRECTIONS:
        a = run([clayfit, "eval", "--preset", path, "--light", light, "--view", view])
        b = run([clayfit, "eval", "--model", fit["model"]["code"], "--light", light, "--view", view]
                + args)
        if a.returncode or b.returncode:
            failures.append(f"eval failed: {a.stderr} {b.stderr}")
            return
        fa, fb = json.loads(a.stdout), json.loads(b.stdout)
        if fa["value"] != fb["value"] or fa["params"] != fb["params"]:
            failures.append(f"round trip at l={light} v={view}: {fa['value']} != {fb['value']}")
        worst = max(worst, max(abs(x - y) for x, y in zip(fa["value"], fb["value"])))
        print(f"l={light} v={view}: f = {fa['value']} (preset) {fb['value']} (fit)")
    print(f"round trip: largest difference {worst} over {len(DIRECTIONS)} direction pairs")


# docs/presets.md, "Tailed lobes in GGX-only formats": one note per tailed
# lobe, the same line in every GGX-only format
GGX_LOSS = re.compile(r"GGX approximation: (< )?(\d+(?:\.\d+)?) % RMS over the lobe")
TAILED_LOBES = {"M2T": ["the specular lobe:"], "M4T": ["the film's lobe:", "the base's lobe"]}


def notes_text(path, fmt):
    """The file's notes as one line (the comments' wrapping undone)."""
    if fmt == "gltf":
        mapping = json.load(open(path, encoding="utf-8"))["asset"]["extras"]["clayfit"]["mapping"]
        return " ".join(" ".join(v) for v in mapping.values())
    text = open(path, encoding="utf-8").read()
    return re.sub(r"\s*\n\s*(?:#\s*)?", " ", text)


def check_tail_notes(fit_path, path, fmt, failures):
    """A tailed fit in a GGX-only format: each tailed lobe's note with the
    loss in numbers; at tail 2 the exact note, loss 0."""
    fit = json.load(open(fit_path, encoding="utf-8"))
    lobes = TAILED_LOBES.get(fit["model"]["code"], [])
    text = notes_text(path, fmt)
    losses = GGX_LOSS.findall(text)
    if len(losses) != len(lobes):
        failures.append(f"{len(losses)} 'GGX approximation: N % RMS over the lobe' notes, "
                        f"expected {len(lobes)} (one per tailed lobe of {fit['model']['code']})")
        return
    for lobe in lobes:
        if lobe not in text:
            failures.append(f"no note of {lobe}")
    if not lobes:
        return
    tail = fit["params"]["tail"]["value"]
    for below, number in losses:
        loss = float(number)
        if tail == 2.0 and (below or loss != 0.0 or "tail gamma 2 is GGX" not in text):
            failures.append(f"tail 2: the note should say GGX exactly with loss 0, got {number} %")
        if tail != 2.0 and not below and not 0.0 < loss < 100.0:
            failures.append(f"tail {tail}: loss {number} % is not a loss")
    print(f"tail {tail}: GGX approximation notes {[b + n + ' %' for b, n in losses]}")


def written_values(path, fmt):
    """The inputs a GGX-only file writes: {name: value text}."""
    if fmt in ("mtlx", "mtlx-openpbr"):
        shader = ET.parse(path).getroot()[0]
        return {e.get("name"): e.get("value") for e in shader}
    if fmt == "blender":
        scope = {}
        source = open(path, encoding="utf-8").read().replace("import bpy", "bpy = None")
        exec(compile(source, path, "exec"), scope)  # noqa: S102 (our own output; bpy stubbed)
        return dict(scope["INPUTS"])
    if fmt == "gltf":
        return json.load(open(path, encoding="utf-8"))["materials"][0]
    return {e.get("name"): e.get("value") for e in ET.parse(path).getroot()[0]}


def check_same_values(clayfit, path, fmt, twin_fit, failures):
    """At tail 2 the file writes what the GGX twin's fit writes."""
    other = path + ".twin"
    result = run([clayfit, "export", twin_fit, "--format", fmt, "-o", other])
    if result.returncode != 0:
        failures.append(f"export of {twin_fit}: exit {result.returncode}")
        return
    a, b = written_values(path, fmt), written_values(other, fmt)
    a.pop("name", None)
    b.pop("name", None)
    if a != b:
        failures.append(f"written values differ from the GGX twin's: {a} != {b}")
    else:
        print(f"the same values as {twin_fit}: {a}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("clayfit")
    parser.add_argument("fit")
    parser.add_argument("format")
    parser.add_argument("out")
    parser.add_argument("--schema", default=os.path.join(os.path.dirname(__file__), "..", "..",
                                                         "data_schema"))
    parser.add_argument("--node-modules")
    parser.add_argument("--same-values-as", metavar="FIT",
                        help="the file must write the values this fit's export writes")
    args = parser.parse_args()
    result = run([args.clayfit, "export", args.fit, "--format", args.format, "-o", args.out])
    print("$ clayfit export", args.fit, "--format", args.format, "-o", args.out)
    print(result.stderr.strip())
    failures = []
    if result.returncode == 0 and args.format != "json":
        check_tail_notes(args.fit, args.out, args.format, failures)
        if args.same_values_as:
            check_same_values(args.clayfit, args.out, args.format, args.same_values_as, failures)
        if failures:  # before a validator that may be absent (exit 77)
            for failure in failures:
                print("FAIL:", failure)
            return 1
    if result.returncode != 0:
        failures.append(f"clayfit export: exit {result.returncode}")
    elif args.format == "json":
        check_json(args.clayfit, args.fit, args.out, args.schema, failures)
    elif args.format in ("mtlx", "mtlx-openpbr"):
        check_mtlx(args.out, args.format == "mtlx-openpbr", failures)
    elif args.format == "mitsuba":
        check_mitsuba(args.out, failures)
    elif args.format == "blender":
        check_blender(args.out, failures)
    elif args.format == "gltf":
        check_gltf(args.out, args.node_modules, failures)
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
