#!/usr/bin/env python3
"""The three.js export (clayfit export --format glsl, docs/shaders.md)
rendered by three.js in headless Chromium (WebGL2 through SwiftShader) and
compared with clayfit's own rendering, pixel by pixel.

For each model: `clayfit synth --images 1 --size 160x120 --format exr
--no-noise --supersample 1 --masks` renders the sphere under its flash (a
point light at the camera's offset) with the parameters of the export
fixtures (make_fits.py). The exported module is rendered by three.js with
the camera of synth's COLMAP model (sparse/0: intrinsics and pose), the
flash of truth.json as its one point light, and the analytic sphere (each
fragment intersects its camera ray with the sphere, so the directions at
pixel centres are exact), into a float render target, read back and written
base64 into the page, which --dump-dom returns. Asserted: the relative RMSE
over the sphere's mask is at most 1e-3 for every model (M0-M4, and the
tailed M2T, M4T with their exact STD lobes, also at a light tail of 30),
and variants with one term deliberately wrong (M4 without 1/eta1^2 or
without the recycling K, M2T with GGX's D for STD's) are caught
(above 1e-3).

The page is bundled into a classic script by esbuild (Chromium refuses ES
modules from file://). Exit 77 (skipped) without Chromium, three or esbuild.

usage: check_shader_threejs.py CLAYFIT NODE_MODULES FITS_DIR WORKDIR
"""
import base64
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
from make_fits import VALUES  # noqa: E402  (the fixtures' parameters)
import scene_compare as sc  # noqa: E402  (camera, flash, the Chromium page)

WIDTH, HEIGHT = 160, 120
# (name, model, parameters): the export fixtures' (make_fits.py), and M2T
# with a light tail, where the masking's continued fraction takes longest
CASES = [(m, m, VALUES[m]) for m in ("M0", "M1", "M2", "M3", "M4", "M2T", "M4T")]
CASES.append(("M2T-tail30", "M2T", dict(VALUES["M2T"], tail=30.0)))
LIMIT = 1e-3
# deliberately wrong terms: (name, model, exact text of the shared body, replacement)
WRONG = [
    ("M4-no-inv-eta2", "M4", "return top + (t1 * inv_eta2) * absorption * base;",
     "return top + t1 * absorption * base;"),
    ("M4-no-recycling", "M4", "float3 k = 1.0 / (1.0 - p.albedo * fbar_i * exp(-4.0 * p.tau));",
     "float3 k = float3(1.0, 1.0, 1.0);"),
    ("M2T-ggx-d", "M2T", "cf_std_d(a2, tail, h.sin2, h.cos2)", "cf_ggx_d(a2, h.sin2, h.cos2)"),
]


def read_exr(path, channels):
    """Pixel values of an EXR through oiiotool --dumpdata (no Python bindings
    needed): a list of rows of tuples."""
    out = subprocess.run(["oiiotool", "--dumpdata", path], capture_output=True, text=True,
                         check=True).stdout
    image = [[None] * WIDTH for _ in range(HEIGHT)]
    for m in re.finditer(r"Pixel \((\d+), (\d+)\):((?: \S+)+)", out):
        x, y = int(m.group(1)), int(m.group(2))
        image[y][x] = tuple(float(v) for v in m.group(3).split())[:channels]
    return image


def synth(clayfit, model, values, folder):
    params = []
    for name, value in values.items():
        text = ",".join(repr(v) for v in value) if isinstance(value, list) else repr(value)
        params += ["--param", f"{name}={text}"]
    subprocess.run([clayfit, "--quiet", "synth", "-o", folder, "--images", "1", "--size",
                    f"{WIDTH}x{HEIGHT}", "--format", "exr", "--no-noise", "--supersample", "1",
                    "--masks", "--model", model] + params, check=True, capture_output=True)


PAGE_SCRIPT = r"""
import * as THREE from 'three';
%(imports)s
const scene = %(scene)s;
const W = scene.width, H = scene.height;
const canvas = document.createElement('canvas');
canvas.width = W; canvas.height = H;
document.body.appendChild(canvas);
const out = document.getElementById('out');
try {
  const renderer = floatRenderer(THREE, canvas);
  renderer.setSize(W, H, false);
  const target = floatTarget(THREE, W, H);
  const cam = colmapCamera(THREE, scene.camera, W, H, 1);
  // any mesh covering the unit sphere: the shader intersects the exact sphere
  const geometry = new THREE.SphereGeometry(1.02, 96, 48);
  const results = {};
  for (const [name, create] of Object.entries(materials)) {
    const material = create(THREE, { lights: [{ position: scene.light, intensity:
      [scene.intensity, scene.intensity, scene.intensity] }],
      sphere: { center: [0, 0, 0], radius: 1 } });
    const world = new THREE.Scene();
    world.add(new THREE.Mesh(geometry, material));
    const pixels = renderFloat(THREE, renderer, target, world, cam, W, H);
    results[name] = base64Floats(pixels);
  }
  out.textContent = 'RESULT ' + JSON.stringify(results) + ' END';
} catch (e) {
  out.textContent = 'ERROR ' + e.message + ' END';
}
"""


def build_page(work, node_modules, modules, scene):
    imports = "\n".join(f"import m{i} from {json.dumps(os.path.abspath(p))};"
                        for i, (_, _, p) in enumerate(modules))
    imports += "\nconst materials = {" + ", ".join(
        f"{json.dumps(name)}: m{i}" for i, (name, _, _) in enumerate(modules)) + "};"
    return sc.build_page(work, node_modules,
                         PAGE_SCRIPT % {"imports": imports, "scene": json.dumps(scene)},
                         "check_shader_threejs")


def compare(reference, mask, data):
    """Relative RMSE over the mask, and the mask's pixels three.js missed."""
    pixels = struct.unpack(f"<{WIDTH * HEIGHT * 4}f", base64.b64decode(data))
    num = den = 0.0
    count = missed = 0
    for y in range(HEIGHT):
        row = HEIGHT - 1 - y  # GL rows start at the bottom
        for x in range(WIDTH):
            if mask[y][x][0] != 1.0:
                continue
            i = 4 * (row * WIDTH + x)
            count += 1
            missed += pixels[i + 3] != 1.0
            for ch in range(3):
                d = pixels[i + ch] - reference[y][x][ch]
                num += d * d
                den += reference[y][x][ch] ** 2
    return math.sqrt(num / den), count, missed


def main():
    clayfit, node_modules, fits, work = sys.argv[1:5]
    browser, skip = sc.chromium_skip(node_modules)
    if skip:
        print(skip)
        return 77
    start = time.time()
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    references, modules, scene = {}, [], None
    for name, model, values in CASES:
        folder = os.path.join(work, "synth-" + name)
        synth(clayfit, model, values, folder)
        references[name] = (read_exr(os.path.join(folder, "images/000.exr"), 3),
                            read_exr(os.path.join(folder, "masks/000.exr"), 1))
        camera = sc.colmap_camera(folder)
        light, intensity = sc.flash(folder, camera)
        this = {"width": WIDTH, "height": HEIGHT, "camera": camera, "light": light,
                "intensity": intensity}
        assert scene is None or scene == this, "synth's scene differs between models"
        scene = this
        fit = os.path.join(fits, model, "fit.json")
        if values is not VALUES[model]:  # the fixture with other values
            doc = json.load(open(fit))
            for key, value in values.items():
                doc["params"][key]["value"] = value
            fit = os.path.join(work, name + ".fit.json")
            with open(fit, "w") as f:
                json.dump(doc, f)
        module = os.path.join(work, name + ".js")
        subprocess.run([clayfit, "--quiet", "export", fit, "--format", "glsl", "-o", module],
                       check=True)
        modules.append((name, name, module))
    for name, model, old, new in WRONG:
        text = open(os.path.join(work, model + ".js")).read()
        assert text.count(old) == 1, f"{name}: the text to break is not in {model}.js"
        path = os.path.join(work, name + ".js")
        with open(path, "w") as f:
            f.write(text.replace(old, new))
        modules.append((name, model, path))
    page = build_page(work, node_modules, modules, scene)
    results = sc.run_chromium(browser, page, 30000, 180, "check_shader_threejs")
    failures = []
    for name, reference, _ in modules:  # a wrong variant is compared with its model's
        error, count, missed = compare(*references[reference], results[name])
        wrong = name != reference
        ok = error > LIMIT if wrong else error <= LIMIT
        print(f"{name}: relative RMSE {error:.3g} over {count} mask pixels ({missed} missed by "
              f"three.js); {'must exceed' if wrong else 'limit'} {LIMIT:g}: "
              f"{'ok' if ok else 'FAIL'}")
        if not ok:
            failures.append(name)
    print(f"{time.time() - start:.1f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
