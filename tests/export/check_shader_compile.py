#!/usr/bin/env python3
"""The shader exports (clayfit export --format glsl / unity, docs/shaders.md)
compiled by Khronos' glslangValidator, and checked to come from one source.

For each fit.json given (one per model), both formats are exported and:
  - the GLSL ES 3.0 vertex and fragment shaders of the three.js module are
    compiled with the declarations three.js' ShaderMaterial prepends
    (glslangValidator -S vert / -S frag);
  - the Unity shader's CGINCLUDE block is compiled by glslang's HLSL front
    end (-D) with stubs in place of Unity's include files (UnityCG.cginc,
    AutoLight.cginc, Lighting.cginc: the few names the glue uses), once per
    entry point (clayfit_vert, clayfit_frag); what the stubs stand for
    (Unity's own macros and shader variants) is not checked;
  - the shared body (between "clayfit shared body: begin" and "end") is the
    same text in both files, and it defines the same functions;
  - the Unity folder: four files, the material names its shader's GUID,
    every GUID is 32 hex digits, and exporting again gives the same bytes;
  - a hostile capture name and path, and fit folder (newlines, a backtick,
    `${`, `*/`, a trailing backslash, U+2028, invalid UTF-8 in the folder) stay in the header's `//` comments:
    the code after the header is the clean export's, byte for byte, and node
    parses the module (node --check).
Exit 77 (skipped) without glslangValidator (apt-get install glslang-tools).

usage: check_shader_compile.py CLAYFIT WORKDIR FIT.json...
"""
import json
import os
import re
import shutil
import subprocess
import sys

THREE_VERTEX_PREFIX = """#version 300 es
precision highp float;
uniform mat4 modelMatrix;
uniform mat4 viewMatrix;
uniform mat4 projectionMatrix;
uniform vec3 cameraPosition;
in vec3 position;
in vec3 normal;
"""
THREE_FRAGMENT_PREFIX = """#version 300 es
precision highp float;
precision highp int;
#define CLAYFIT_MAX_LIGHTS 8
#define CLAYFIT_ANALYTIC_SPHERE 1
uniform vec3 cameraPosition;
"""
UNITY_STUBS = """// stand-ins for the names UnityCG.cginc, AutoLight.cginc and Lighting.cginc give
#define UNITY_PI 3.14159265359
float4x4 unity_ObjectToWorld;
float4x4 unity_WorldToObject;
float4x4 unity_MatrixVP;
float4 _WorldSpaceCameraPos;
float4 _WorldSpaceLightPos0;
float4 _LightColor0;
struct appdata_base { float4 vertex : POSITION; float3 normal : NORMAL; float4 texcoord : TEXCOORD0; };
float4 UnityObjectToClipPos(float4 v) { return mul(unity_MatrixVP, mul(unity_ObjectToWorld, v)); }
float3 UnityObjectToWorldNormal(float3 n) { return normalize(mul(n, (float3x3)unity_WorldToObject)); }
float3 UnityWorldSpaceLightDir(float3 p) { return _WorldSpaceLightPos0.xyz - p * _WorldSpaceLightPos0.w; }
#define LIGHTING_COORDS(a, b) float3 light_coord : TEXCOORD##a;
#define TRANSFER_VERTEX_TO_FRAGMENT(o) o.light_coord = o.world_pos;
#define UNITY_LIGHT_ATTENUATION(name, i, p) float name = 1.0 / (1.0 + dot(i.light_coord, i.light_coord));
"""
BODY = re.compile(r"// ---- clayfit shared body: begin.*?// ---- clayfit shared body: end\n", re.S)
FUNCTION = re.compile(r"^(?:float[234]?|cf_\w+) (cf_\w+)\(", re.M)


def compile_glsl(name, source, stage, work):
    path = os.path.join(work, f"{name}.{stage}")
    with open(path, "w") as f:
        f.write(source)
    r = subprocess.run(["glslangValidator", "-S", stage, path], capture_output=True, text=True)
    return None if r.returncode == 0 else f"{path}: {r.stdout}{r.stderr}"


def compile_hlsl(name, source, stage, entry, work):
    path = os.path.join(work, f"{name}.{entry}.hlsl")
    with open(path, "w") as f:
        f.write(source)
    r = subprocess.run(["glslangValidator", "-D", "-e", entry, "-S", stage, "-V", "-o",
                        os.devnull, path], capture_output=True, text=True)
    return None if r.returncode == 0 else f"{path}: {r.stdout}{r.stderr}"


def template(js, name):
    m = re.search(r"export const " + name + r" = `(.*?)`;", js, re.S)
    return m.group(1) if m else None


def check_model(clayfit, fit, work, failures):
    name = os.path.basename(os.path.dirname(fit))
    js_path = os.path.join(work, f"{name}.js")
    unity = os.path.join(work, f"{name}-unity")
    for fmt, out in (("glsl", js_path), ("unity", unity)):
        r = subprocess.run([clayfit, "--quiet", "export", fit, "--format", fmt, "-o", out],
                           capture_output=True, text=True)
        if r.returncode != 0:
            failures.append(f"{name} {fmt}: exit {r.returncode}: {r.stderr}")
            return
    js = open(js_path, encoding="utf-8").read()
    vertex, fragment = template(js, "vertexShader"), template(js, "fragmentShader")
    if vertex is None or fragment is None:
        failures.append(f"{name}: no vertexShader / fragmentShader in {js_path}")
        return
    for stage, prefix, text in (("vert", THREE_VERTEX_PREFIX, vertex),
                                ("frag", THREE_FRAGMENT_PREFIX, fragment)):
        error = compile_glsl(name, prefix + text, stage, work)
        if error:
            failures.append(error)

    shader = open(os.path.join(unity, "clayfit.shader"), encoding="utf-8").read()
    block = re.search(r"CGINCLUDE\n(.*?)\n\s*ENDCG", shader, re.S)
    if not block:
        failures.append(f"{name}: no CGINCLUDE block in the Unity shader")
        return
    hlsl = re.sub(r'^\s*#include "[A-Za-z]+\.cginc"\s*$', "", block.group(1), flags=re.M)
    hlsl = UNITY_STUBS + hlsl
    for stage, entry in (("vert", "clayfit_vert"), ("frag", "clayfit_frag")):
        error = compile_hlsl(name, hlsl, stage, entry, work)
        if error:
            failures.append(error)

    # one source: the same body text, the same functions
    body_glsl, body_hlsl = BODY.search(fragment), BODY.search(shader)
    if not body_glsl or not body_hlsl:
        failures.append(f"{name}: the shared body's markers are missing")
        return
    if body_glsl.group(0) != body_hlsl.group(0):
        failures.append(f"{name}: the shared body differs between GLSL and HLSL")
    functions = FUNCTION.findall(body_glsl.group(0))
    if len(functions) < 10 or functions != FUNCTION.findall(body_hlsl.group(0)):
        failures.append(f"{name}: function lists differ or are short: {functions}")
    print(f"{name}: GLSL vert+frag, HLSL clayfit_vert+clayfit_frag compiled; shared body "
          f"{len(body_glsl.group(0))} chars, {len(functions)} functions, identical")

    # the Unity folder
    files = sorted(os.listdir(unity))
    expected = ["clayfit.mat", "clayfit.mat.meta", "clayfit.shader", "clayfit.shader.meta"]
    if files != expected:
        failures.append(f"{name}: Unity folder holds {files}, expected {expected}")
        return
    guids = {}
    for meta in ("clayfit.shader.meta", "clayfit.mat.meta"):
        m = re.search(r"^guid: ([0-9a-f]{32})$", open(os.path.join(unity, meta)).read(), re.M)
        if not m:
            failures.append(f"{name}: {meta} has no 32-hex-digit guid")
            return
        guids[meta] = m.group(1)
    if guids["clayfit.shader.meta"] == guids["clayfit.mat.meta"]:
        failures.append(f"{name}: the shader and the material share a GUID")
    mat = open(os.path.join(unity, "clayfit.mat")).read()
    if f"m_Shader: {{fileID: 4800000, guid: {guids['clayfit.shader.meta']}, type: 3}}" not in mat:
        failures.append(f"{name}: clayfit.mat does not name the shader's GUID")
    again = unity + "-again"
    subprocess.run([clayfit, "--quiet", "export", fit, "--format", "unity", "-o", again],
                   check=True)
    for f in expected:
        if open(os.path.join(unity, f), "rb").read() != open(os.path.join(again, f), "rb").read():
            failures.append(f"{name}: exporting again changed {f}")


HOSTILE = "x`${alert(1)}`*/\n}\nexport const evil = 1; // \u2028\\"


def code_after_header(data, first):
    """The header (lines before `first`) must be comments; returns the rest."""
    head, sep, rest = data.partition(first)
    for line in head.split(b"\n"):
        if line and not line.startswith(b"//"):
            return None
    return sep + rest if sep else None


def check_hostile(clayfit, fit, work, failures):
    doc = json.load(open(fit))
    doc["capture"] = dict(doc["capture"], name=HOSTILE, path=HOSTILE + "\\")
    # the fit's folder: a newline, a backtick, `${`, a backslash, invalid UTF-8
    folder = os.path.join(os.fsencode(work), b"hostile\n`${x}`\\\xff")
    os.makedirs(folder)
    hostile_fit = os.path.join(folder, b"fit.json")
    with open(hostile_fit, "w") as f:
        json.dump(doc, f)
    pairs = []
    for fit_path, tag in ((os.fsencode(fit), "clean"), (hostile_fit, "hostile")):
        js, unity = os.path.join(work, f"{tag}.mjs"), os.path.join(work, f"{tag}-unity")
        for fmt, out in (("glsl", js), ("unity", unity)):
            r = subprocess.run([clayfit, "--quiet", "export", fit_path, "--format", fmt, "-o",
                                out], capture_output=True)
            if r.returncode != 0:
                failures.append(f"hostile: {tag} {fmt}: exit {r.returncode}")
                return
        pairs.append((open(js, "rb").read(), open(os.path.join(unity, "clayfit.shader"),
                                                       "rb").read(), js))
    (clean_js, clean_shader, _), (js, shader, js_path) = pairs
    for name, a, b, first in (("glsl", clean_js, js, b"export const clayfit"),
                              ("unity", clean_shader, shader, b'Shader "')):
        rest = code_after_header(b, first)
        if rest is None or rest != code_after_header(a, first):
            failures.append(f"hostile: {name}: text escaped the header's comments")
    if b"\n}\nexport const evil" in js:
        failures.append("hostile: glsl: the name is in the module unescaped")
    if shutil.which("node"):
        r = subprocess.run(["node", "--check", js_path], capture_output=True, text=True)
        if r.returncode != 0:
            failures.append(f"hostile: node --check: {r.stderr}")
    print("hostile name and path: header comments only, code identical to the clean export's")


def main():
    clayfit, work, fits = sys.argv[1], sys.argv[2], sys.argv[3:]
    if not shutil.which("glslangValidator"):
        print("SKIP: no glslangValidator (apt-get install glslang-tools)")
        return 77
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures = []
    for fit in fits:
        check_model(clayfit, fit, work, failures)
    check_hostile(clayfit, fits[-1], work, failures)
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
