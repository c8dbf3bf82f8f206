#!/usr/bin/env python3
"""Preset fidelity in three.js (docs/fidelity.md): for each fit.json, the glTF
preset loaded by three.js' GLTFLoader (MeshPhysicalMaterial) and rendered in
headless Chromium (WebGL2 through SwiftShader), against clayfit's own image
formation of the same scene, pixel by pixel inside the sphere.

usage: threejs_fidelity.py CLAYFIT NODE_MODULES WORKDIR FIT.json [FIT.json ...]
           [--size WxH] [--supersample S] [--flash-offset x,y,z]
           [--set PROPERTY=VALUE ...] [--max-rmse X]
           [--environment EXR [--environment-lights K] [--environment-rotation R]
            [--rotation R] [--orientation DEG]] [--synth-cache DIR]

The scene is blender_fidelity.py's: `clayfit synth` of one noiseless float
image of the fit's model and values (camera 0: distance 5, 20 degrees up; the
flash at --flash-offset in camera coordinates, default 2.5,-1.5,0), S x S
samples per pixel (default 4). three.js renders the preset's material (the
loaded glTF's, with any --set applied to it, e.g. color=0.5,0.4,0.3 or
ior=1.5) on a finely tessellated unit sphere (SphereGeometry 512 x 256: its
facets are 7.5e-5 from the sphere) with the COLMAP camera and the flash as a
PointLight of intensity I (candela in three.js r155+: with decay 2 and no
cutoff distance, E = I/d^2 as clayfit's), into a float render target S times
larger, averaged over S x S blocks in the page (the synth's sub-pixel grid),
no tone mapping, linear output. The compared pixels, the relative RMSE, the
sum ratio, the RMSE after the best gain and the difference image
(WORKDIR/NAME/diff.png) are blender_compare.py's (scripts/scene_compare.py). Prints one JSON line and a
Markdown row per fit. With --max-rmse, exits 1 when a relative RMSE is above
it. Exit 77 without Chromium, oiiotool, or three and esbuild in NODE_MODULES.

With --environment (the HDRI rows), the flash is replaced by the map: K
median-cut lights in clayfit (synth --environment, default K 1024),
scene.environment in three.js (EXRLoader, negative values as 0, PMREM as three.js makes it; scene.environmentRotation from
truth.json's rotation: scene_compare.THREE_FROM_MAP). --orientation DEG is the
one-patch map check instead of the comparison.
"""
import argparse
import base64
import json
import os
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scene_compare as sc  # noqa: E402

PROG = "threejs_fidelity"


PAGE_SCRIPT = r"""
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { EXRLoader } from 'three/addons/loaders/EXRLoader.js';
const jobs = %(jobs)s;
const out = document.getElementById('out');

function setProperty(material, key, text) {
  const values = text.split(',').map(Number);
  if (!(key in material)) throw new Error('the material has no property ' + key);
  if (material[key] && material[key].isColor) material[key].setRGB(values[0], values[1], values[2]);
  else material[key] = values[0];
  material.needsUpdate = true;
}

// the map of job.environment as scene.environment: EXRLoader's float data (three.js'
// equirectangular convention is clayfit's, scene_compare.THREE_FROM_MAP) with its
// negative values as 0 (as clayfit counts them, src/capture/envmap.h),
// equirectangular, turned by scene.environmentRotation so that the world's rotation is
// job.environment.rotation (WebGLMaterials uses the transpose of the Euler's matrix)
function setEnvironment(world, env) {
  const raw = Uint8Array.from(atob(env.exr), (ch) => ch.charCodeAt(0));
  const loader = new EXRLoader();
  loader.setDataType(THREE.FloatType);
  const map = loader.parse(raw.buffer);
  const data = map.data;
  for (let i = 0; i < data.length; ++i) if (!(data[i] > 0)) data[i] = 0;
  const texture = new THREE.DataTexture(data, map.width, map.height, map.format, map.type);
  texture.colorSpace = THREE.LinearSRGBColorSpace;
  texture.minFilter = texture.magFilter = THREE.LinearFilter;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.mapping = THREE.EquirectangularReflectionMapping;
  texture.needsUpdate = true;
  world.environment = texture;
  const r = env.rotation, m = new THREE.Matrix4().set(r[0][0], r[0][1], r[0][2], 0,
    r[1][0], r[1][1], r[1][2], 0, r[2][0], r[2][1], r[2][2], 0, 0, 0, 0, 1);
  world.environmentRotation.setFromRotationMatrix(m, 'XYZ');
  world.environmentIntensity = 1;
  return texture;
}

function render(renderer, job, material) {
  const S = job.supersample, W = job.width * S, H = job.height * S;
  const target = floatTarget(THREE, W, H);
  const cam = colmapCamera(THREE, job.camera, W, H, S);
  const world = new THREE.Scene();
  world.add(new THREE.Mesh(new THREE.SphereGeometry(1, 512, 256), material));
  let texture = null;
  if (job.environment) {
    texture = setEnvironment(world, job.environment);
  } else {
    // candela: E = I / d^2 at decay 2 and distance 0 (no cutoff window)
    const light = new THREE.PointLight(0xffffff, job.intensity, 0, 2);
    light.position.set(job.light[0], job.light[1], job.light[2]);
    world.add(light);
  }
  const pixels = renderFloat(THREE, renderer, target, world, cam, W, H);
  target.dispose();
  if (texture) texture.dispose();
  // average S x S blocks; rows top first (GL's start at the bottom); RGB
  const w = job.width, h = job.height, res = new Float32Array(w * h * 3);
  for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) for (let ch = 0; ch < 3; ++ch) {
    let sum = 0;
    for (let j = 0; j < S; ++j) for (let i = 0; i < S; ++i)
      sum += pixels[4 * ((H - 1 - (y * S + j)) * W + x * S + i) + ch];
    res[3 * (y * w + x) + ch] = sum / (S * S);
  }
  return base64Floats(res);
}

async function main() {
  const canvas = document.createElement('canvas');
  document.body.appendChild(canvas);
  const renderer = floatRenderer(THREE, canvas);
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  const loader = new GLTFLoader();
  const results = {};
  for (const job of jobs) {
    const gltf = await loader.parseAsync(job.gltf, '');
    let material = null;
    gltf.scene.traverse((o) => { if (o.isMesh) material = o.material; });
    if (!material) throw new Error(job.name + ': no mesh in the glTF');
    for (const [key, value] of job.set) setProperty(material, key, value);
    results[job.name] = { type: material.type, pixels: render(renderer, job, material) };
  }
  return results;
}
main().then((results) => { out.textContent = 'RESULT ' + JSON.stringify(results) + ' END'; },
            (e) => { out.textContent = 'ERROR ' + e.message + ' END'; });
"""


def prepare(a, fit_path):
    """Export, synth and the page's job for one fit."""
    name, work, fit = sc.fit_folder(a.workdir, fit_path)
    gltf = os.path.join(work, "preset.gltf")
    sc.run([a.clayfit, "--quiet", "export", fit_path, "--format", "gltf", "-o", gltf], "export",
           PROG)
    synth = os.path.join(work, "synth")
    synth_s = sc.synth_scene(a, fit, synth, PROG)
    camera = sc.colmap_camera(synth)
    w, h = map(int, a.size.split("x"))
    job = {"name": name, "gltf": open(gltf, encoding="utf-8").read(), "width": w, "height": h,
           "supersample": a.supersample, "camera": camera,
           "set": [s.split("=", 1) for s in a.set]}
    env = sc.truth_environment(synth)
    if env:
        rotation = env["rotation"]
        if a.rotation:
            v = [float(x) for x in a.rotation.split(",")]
            rotation = [v[0:3], v[3:6], v[6:9]]
        with open(env["path"], "rb") as f:
            exr = base64.b64encode(f.read()).decode("ascii")
        job["environment"] = {"exr": exr, "rotation": sc.matmul(rotation, sc.THREE_FROM_MAP)}
    else:
        job["light"], job["intensity"] = sc.flash(synth, camera)
    return {"name": name, "model": fit["model"]["code"], "work": work, "synth": synth,
            "synth_s": synth_s}, job


def main():
    p = argparse.ArgumentParser(prog="threejs_fidelity.py")
    p.add_argument("clayfit")
    p.add_argument("node_modules")
    p.add_argument("workdir")
    p.add_argument("fits", nargs="+")
    sc.add_scene_arguments(p, "three.js", "scene.environment in three.js")
    p.add_argument("--margin", type=int, default=2)
    a = p.parse_args()
    browser, skip = sc.chromium_skip(a.node_modules)
    if skip:
        print(skip)
        return 77
    for s in a.set:
        if "=" not in s:
            raise SystemExit(f"threejs_fidelity: --set {s!r}: expected PROPERTY=VALUE")
    os.makedirs(a.workdir, exist_ok=True)
    cases, jobs = zip(*(prepare(a, fit) for fit in a.fits))
    t0 = time.monotonic()
    page = sc.build_page(a.workdir, os.path.abspath(a.node_modules),
                         PAGE_SCRIPT % {"jobs": json.dumps(list(jobs))}, PROG)
    results = sc.run_chromium(browser, page, 120000, 600, PROG)
    three_s = time.monotonic() - t0
    failed = False
    for case, job in zip(cases, jobs):
        w, h = job["width"], job["height"]
        c = sc.exr_values(os.path.join(case["synth"], "images", "000.exr"), 3, PROG)
        m = sc.exr_values(os.path.join(case["synth"], "masks", "000.exr"), 1, PROG)
        if len(c) != 3 * w * h or len(m) != w * h:
            raise SystemExit(f"threejs_fidelity: {case['name']}: the synth images are not {w}x{h}")
        raw = base64.b64decode(results[case["name"]]["pixels"])
        b = struct.unpack(f"<{3 * w * h}f", raw)
        if a.orientation is not None:
            failed = sc.report_orientation(case["name"], "three.js", c, b, m, case["synth"], w, h,
                                           3, a.orientation, PROG) or failed
            continue
        r, inside, mean = sc.compare(c, b, m, w, h, a.margin, 3, PROG)
        sc.write_png(os.path.join(case["work"], "diff.png"), w, h,
                     sc.diff_values(c, b, inside, w, h, mean, 3))
        r.update({"fit": case["name"], "model": case["model"],
                  "material": results[case["name"]]["type"], "synth_s": round(case["synth_s"], 2),
                  "threejs_s_all": round(three_s, 2)})
        failed = sc.report(r, a.max_rmse) or failed
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
