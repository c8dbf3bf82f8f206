#!/usr/bin/env python3
"""Preset fidelity in three.js (docs/fidelity.md): for each fit.json, the glTF
preset loaded by three.js' GLTFLoader (MeshPhysicalMaterial) and rendered in
headless Chromium (WebGL2 through SwiftShader), against clayfit's own image
formation of the same scene, pixel by pixel inside the sphere.

usage: threejs_fidelity.py CLAYFIT NODE_MODULES WORKDIR FIT.json [FIT.json ...]
           [--size WxH] [--supersample S] [--flash-offset x,y,z]
           [--set PROPERTY=VALUE ...] [--max-rmse X]

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
(WORKDIR/NAME/diff.png) are blender_compare.py's. Prints one JSON line and a
Markdown row per fit. With --max-rmse, exits 1 when a relative RMSE is above
it. Exit 77 without Chromium, oiiotool, or three and esbuild in NODE_MODULES.
"""
import argparse
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
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def run(command, what, **kw):
    result = subprocess.run(command, capture_output=True, text=True, timeout=600, **kw)
    if result.returncode != 0:
        sys.stderr.write(result.stdout[-3000:] + result.stderr[-3000:])
        raise SystemExit(f"threejs_fidelity: {what} failed (exit {result.returncode})")
    return result.stdout


def synth_params(fit):
    out = []
    for name, p in fit["params"].items():
        v = p["value"]
        text = ",".join(repr(float(x)) for x in v) if isinstance(v, list) else repr(float(v))
        out += ["--param", f"{name}={text}"]
    return out


def exr_values(path, channels):
    """The first `channels` values of every pixel of an EXR, top row first,
    through oiiotool --dumpdata (no Python bindings needed)."""
    out = run(["oiiotool", "--dumpdata", path], "oiiotool --dumpdata")
    pixels = {}
    for m in re.finditer(r"Pixel \((\d+), (\d+)\):((?: \S+)+)", out):
        pixels[(int(m.group(2)), int(m.group(1)))] = [float(v) for v in m.group(3).split()][:channels]
    return [v for key in sorted(pixels) for v in pixels[key]]


def write_png(path, w, h, rgb):
    """An 8-bit RGB PNG of values in [0, 1] (zlib only)."""
    raw = b"".join(b"\0" + bytes(int(round(255 * v)) for v in rgb[3 * w * y:3 * w * (y + 1)])
                   for y in range(h))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def colmap_camera(folder):
    cam = [l for l in open(os.path.join(folder, "sparse/0/cameras.txt")).read().split("\n")
           if l and not l.startswith("#")][0].split()
    if cam[1] != "PINHOLE":
        raise SystemExit(f"threejs_fidelity: camera model {cam[1]}, expected PINHOLE")
    fx, fy, cx, cy = map(float, cam[4:8])
    img = [l for l in open(os.path.join(folder, "sparse/0/images.txt")).read().split("\n")
           if l and not l.startswith("#")][0].split()
    qw, qx, qy, qz, tx, ty, tz = map(float, img[1:8])
    r = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
         [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
         [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    t = [tx, ty, tz]
    centre = [-sum(r[k][i] * t[k] for k in range(3)) for i in range(3)]
    return {"fx": fx, "fy": fy, "cx": cx, "cy": cy, "r": r, "centre": centre}


def flash(folder, camera):
    truth = json.load(open(os.path.join(folder, "truth.json")))
    offset, r = truth["flash"]["offset"], camera["r"]
    position = [camera["centre"][i] + sum(r[k][i] * offset[k] for k in range(3))
                for i in range(3)]
    return position, truth["flash"]["intensity"]


PAGE_SCRIPT = r"""
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
const jobs = %(jobs)s;
const out = document.getElementById('out');

function setProperty(material, key, text) {
  const values = text.split(',').map(Number);
  if (!(key in material)) throw new Error('the material has no property ' + key);
  if (material[key] && material[key].isColor) material[key].setRGB(values[0], values[1], values[2]);
  else material[key] = values[0];
  material.needsUpdate = true;
}

function render(renderer, job, material) {
  const S = job.supersample, W = job.width * S, H = job.height * S;
  const target = new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType,
    format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    depthBuffer: true });
  // the COLMAP camera (x right, y down, z forward) -> three.js' (y up, z back)
  const cam = new THREE.PerspectiveCamera(30, W / H, 0.1, 100);
  const r = job.camera.r, c = job.camera.centre;
  const basis = new THREE.Matrix4().makeBasis(new THREE.Vector3(r[0][0], r[0][1], r[0][2]),
    new THREE.Vector3(-r[1][0], -r[1][1], -r[1][2]), new THREE.Vector3(-r[2][0], -r[2][1], -r[2][2]));
  cam.quaternion.setFromRotationMatrix(basis);
  cam.position.set(c[0], c[1], c[2]);
  cam.updateMatrixWorld(true);
  const n = 0.1, f = 100, k = job.camera;
  const fx = k.fx * S, fy = k.fy * S, cx = k.cx * S, cy = k.cy * S;
  cam.projectionMatrix.set(2 * fx / W, 0, 1 - 2 * cx / W, 0,
                           0, 2 * fy / H, 2 * cy / H - 1, 0,
                           0, 0, -(f + n) / (f - n), -2 * f * n / (f - n),
                           0, 0, -1, 0);
  cam.projectionMatrixInverse.copy(cam.projectionMatrix).invert();
  const world = new THREE.Scene();
  world.add(new THREE.Mesh(new THREE.SphereGeometry(1, 512, 256), material));
  // candela: E = I / d^2 at decay 2 and distance 0 (no cutoff window)
  const light = new THREE.PointLight(0xffffff, job.intensity, 0, 2);
  light.position.set(job.light[0], job.light[1], job.light[2]);
  world.add(light);
  renderer.setRenderTarget(target);
  renderer.setClearColor(0x000000, 0);
  renderer.clear();
  renderer.render(world, cam);
  const pixels = new Float32Array(W * H * 4);
  renderer.readRenderTargetPixels(target, 0, 0, W, H, pixels);
  target.dispose();
  // average S x S blocks; rows top first (GL's start at the bottom); RGB
  const w = job.width, h = job.height, res = new Float32Array(w * h * 3);
  for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) for (let ch = 0; ch < 3; ++ch) {
    let sum = 0;
    for (let j = 0; j < S; ++j) for (let i = 0; i < S; ++i)
      sum += pixels[4 * ((H - 1 - (y * S + j)) * W + x * S + i) + ch];
    res[3 * (y * w + x) + ch] = sum / (S * S);
  }
  const bytes = new Uint8Array(res.buffer);
  let text = '';
  for (let i = 0; i < bytes.length; i += 8192)
    text += String.fromCharCode.apply(null, bytes.subarray(i, i + 8192));
  return btoa(text);
}

async function main() {
  const canvas = document.createElement('canvas');
  document.body.appendChild(canvas);
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  const gl = renderer.getContext();
  if (!(gl instanceof WebGL2RenderingContext)) throw new Error('no WebGL2');
  if (!gl.getExtension('EXT_color_buffer_float')) throw new Error('no EXT_color_buffer_float');
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  renderer.setPixelRatio(1);
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


def build_page(work, node_modules, jobs):
    entry = os.path.join(work, "entry.js")
    with open(entry, "w") as f:
        f.write(PAGE_SCRIPT % {"jobs": json.dumps(jobs)})
    env = dict(os.environ, NODE_PATH=node_modules)
    esbuild = os.path.join(node_modules, ".bin", "esbuild")
    run([esbuild, entry, "--bundle", "--format=iife", "--log-level=warning",
         "--outfile=" + os.path.join(work, "bundle.js")], "esbuild", env=env)
    page = os.path.join(work, "index.html")
    with open(page, "w") as f:
        f.write('<!doctype html><html><body><pre id="out">PENDING</pre>'
                '<script src="bundle.js"></script></body></html>')
    return page


def run_chromium(browser, page):
    cmd = [browser, "--headless", "--no-sandbox", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--hide-scrollbars",
           "--virtual-time-budget=120000", "--dump-dom", "file://" + page]
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    m = re.search(r"(RESULT|ERROR) (.*?) END", dom.stdout, re.S)
    if not m:
        raise SystemExit("threejs_fidelity: the page did not finish: " + dom.stderr[-2000:])
    if m.group(1) == "ERROR":
        raise SystemExit("threejs_fidelity: the page failed: " + m.group(2))
    return json.loads(m.group(2))


def erode(mask, w, h, steps):
    for _ in range(steps):
        out = [False] * (w * h)
        for y in range(1, h - 1):
            row = y * w
            for x in range(1, w - 1):
                i = row + x
                out[i] = mask[i] and mask[i - 1] and mask[i + 1] and mask[i - w] and mask[i + w]
        mask = out
    return mask


def compare(c, m, b, w, h, margin, diff_png):
    """blender_compare.py's figures: c clayfit's RGB, m the mask, b three.js' RGB."""
    mask = erode([m[i] >= 1.0 - 1e-6 for i in range(w * h)], w, h, margin)
    inside = [i for i in range(w * h) if mask[i]]
    if not inside:
        raise SystemExit("threejs_fidelity: the mask leaves no pixel")
    bc = bb2 = sum_b = sum_c = peak = max_d = 0.0
    e2k, y2k = [0.0] * 3, [0.0] * 3
    for i in inside:
        for k in range(3):
            cv, bv = c[3 * i + k], b[3 * i + k]
            if not (math.isfinite(cv) and math.isfinite(bv)):
                raise SystemExit(f"threejs_fidelity: pixel {i % w}, {i // w} is not finite")
            d = bv - cv
            e2k[k] += d * d
            y2k[k] += cv * cv
            bc += bv * cv
            bb2 += bv * bv
            sum_b += bv
            sum_c += cv
            peak = max(peak, cv)
            max_d = max(max_d, abs(d))
    e2, y2 = sum(e2k), sum(y2k)
    gain = bc / bb2 if bb2 > 0.0 else 0.0
    after = max(0.0, gain * gain * bb2 - 2.0 * gain * bc + y2)
    if diff_png:  # grey 0.5 +/- 0.5 at +/- 25 % of clayfit's mean, black outside
        scale = 0.25 * sum_c / (3 * len(inside))
        img = [0.0] * (3 * w * h)
        for i in inside:
            for k in range(3):
                img[3 * i + k] = min(1.0, max(0.0, 0.5 + 0.5 * (b[3 * i + k] - c[3 * i + k]) / scale))
        write_png(diff_png, w, h, img)
    return {"pixels": len(inside), "relative_rmse": math.sqrt(e2 / y2),
            "sum_ratio": sum_b / sum_c, "relative_rmse_after_gain": math.sqrt(after / y2),
            "relative_rmse_per_channel": [math.sqrt(e2k[k] / y2k[k]) for k in range(3)],
            "max_abs_diff_over_peak": max_d / peak}


def prepare(a, fit_path):
    """Export, synth and the page's job for one fit."""
    name = os.path.basename(os.path.dirname(os.path.abspath(fit_path)))
    work = os.path.join(a.workdir, name)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    with open(fit_path, encoding="utf-8") as f:
        fit = json.load(f)
    gltf = os.path.join(work, "preset.gltf")
    run([a.clayfit, "--quiet", "export", fit_path, "--format", "gltf", "-o", gltf], "export")
    synth = os.path.join(work, "synth")
    t0 = time.monotonic()
    run([a.clayfit, "--quiet", "synth", "-o", synth, "--model", fit["model"]["code"],
         *synth_params(fit), "--images", "1", "--size", a.size, "--format", "exr",
         "--no-noise", "--masks", "--supersample", str(a.supersample),
         "--flash-offset", a.flash_offset], "clayfit synth")
    synth_s = time.monotonic() - t0
    camera = colmap_camera(synth)
    light, intensity = flash(synth, camera)
    w, h = map(int, a.size.split("x"))
    job = {"name": name, "gltf": open(gltf, encoding="utf-8").read(), "width": w, "height": h,
           "supersample": a.supersample, "camera": camera, "light": light,
           "intensity": intensity, "set": [s.split("=", 1) for s in a.set]}
    return {"name": name, "model": fit["model"]["code"], "work": work, "synth": synth,
            "synth_s": synth_s}, job


def main():
    p = argparse.ArgumentParser(prog="threejs_fidelity.py")
    p.add_argument("clayfit")
    p.add_argument("node_modules")
    p.add_argument("workdir")
    p.add_argument("fits", nargs="+")
    p.add_argument("--size", default="320x240")
    p.add_argument("--supersample", type=int, default=4)
    p.add_argument("--flash-offset", default="2.5,-1.5,0")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--margin", type=int, default=2)
    p.add_argument("--max-rmse", type=float)
    a = p.parse_args()
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if not browser:
        print("SKIP: no Chromium (apt-get install chromium)")
        return 77
    for need in ("three/package.json", ".bin/esbuild"):
        if not os.path.exists(os.path.join(a.node_modules, need)):
            print(f"SKIP: no {need} in {a.node_modules} (scripts/install-deps.sh installs it)")
            return 77
    if not shutil.which("oiiotool"):
        print("SKIP: no oiiotool")
        return 77
    for s in a.set:
        if "=" not in s:
            raise SystemExit(f"threejs_fidelity: --set {s!r}: expected PROPERTY=VALUE")
    os.makedirs(a.workdir, exist_ok=True)
    cases, jobs = zip(*(prepare(a, fit) for fit in a.fits))
    t0 = time.monotonic()
    results = run_chromium(browser, build_page(a.workdir, os.path.abspath(a.node_modules),
                                               list(jobs)))
    three_s = time.monotonic() - t0
    failed = False
    for case, job in zip(cases, jobs):
        w, h = job["width"], job["height"]
        c = exr_values(os.path.join(case["synth"], "images", "000.exr"), 3)
        m = exr_values(os.path.join(case["synth"], "masks", "000.exr"), 1)
        if len(c) != 3 * w * h or len(m) != w * h:
            raise SystemExit(f"threejs_fidelity: {case['name']}: the synth images are not {w}x{h}")
        raw = base64.b64decode(results[case["name"]]["pixels"])
        b = struct.unpack(f"<{3 * w * h}f", raw)
        r = compare(c, m, b, w, h, a.margin, os.path.join(case["work"], "diff.png"))
        r.update({"fit": case["name"], "model": case["model"],
                  "material": results[case["name"]]["type"], "synth_s": round(case["synth_s"], 2),
                  "threejs_s_all": round(three_s, 2)})
        print(json.dumps(r))
        print(f"| {r['fit']} | {100 * r['relative_rmse']:.2f} % | {r['sum_ratio']:.4f} | "
              f"{100 * r['relative_rmse_after_gain']:.2f} % | {r['pixels']} |")
        if a.max_rmse is not None and not r["relative_rmse"] <= a.max_rmse:
            print(f"FAIL: {r['fit']}: relative RMSE {r['relative_rmse']:.4g} is above "
                  f"{a.max_rmse:.4g}")
            failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
