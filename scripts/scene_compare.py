"""What the renderer comparisons share (docs/fidelity.md, docs/shaders.md):
the scene of a `clayfit synth` capture (camera 0 of sparse/0, the flash of
truth.json), the synth of a fit, the comparison of two renderings inside the
sphere and its difference image, and the headless Chromium + esbuild harness
of the three.js pages.

Plain Python 3, no numpy: blender_compare.py imports it in Blender's Python
(whose site-packages may have none); the others from system python3. Each
caller puts this folder on sys.path.
"""
import hashlib
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


def run(command, what, prog, **kw):
    """A command's stdout; its output's tail and `prog: what failed` on failure."""
    result = subprocess.run(command, capture_output=True, text=True, timeout=600, **kw)
    if result.returncode != 0:
        sys.stderr.write(result.stdout[-3000:] + result.stderr[-3000:])
        raise SystemExit(f"{prog}: {what} failed (exit {result.returncode})")
    return result.stdout


def synth_params(fit):
    """--param name=value for every parameter of a fit.json's params."""
    out = []
    for name, p in fit["params"].items():
        v = p["value"]
        text = ",".join(repr(float(x)) for x in v) if isinstance(v, list) else repr(float(v))
        out += ["--param", f"{name}={text}"]
    return out


def fit_folder(workdir, fit_path):
    """A fit's name (its folder's), its fresh WORKDIR/NAME and its fit.json."""
    name = os.path.basename(os.path.dirname(os.path.abspath(fit_path)))
    work = os.path.join(workdir, name)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    with open(fit_path, encoding="utf-8") as f:
        return name, work, json.load(f)


def synth_fit(clayfit, fit, folder, size, supersample, flash_offset, prog, environment=None,
              cache=None):
    """The fidelity scene: one noiseless float image of the fit's model and
    values with its mask (camera 0: distance 5, 20 degrees up), lit by the
    flash or, with `environment` (synth's --environment options as a list),
    by a map's median-cut lights instead. With `cache` (a folder), a synth
    of the same command is copied from there (K = 1024 median-cut lights
    cost minutes for the tailed rungs; Blender's and three.js' rows share them)."""
    light = environment if environment else ["--flash-offset", flash_offset]
    args = ["--model", fit["model"]["code"], *synth_params(fit), "--images", "1", "--size", size,
            "--format", "exr", "--no-noise", "--masks", "--supersample", str(supersample), *light]
    key = None
    if cache:
        stamp = os.stat(clayfit).st_mtime_ns
        key = os.path.join(cache, hashlib.sha1(json.dumps([clayfit, stamp, args]).encode())
                           .hexdigest())
        if os.path.isdir(key):
            shutil.rmtree(folder, ignore_errors=True)
            shutil.copytree(key, folder)
            return
    run([clayfit, "--quiet", "synth", "-o", folder, *args], "clayfit synth", prog)
    if key:
        # the map's path in truth.json is relative to the folder: absolute in the copy
        truth_path = os.path.join(folder, "truth.json")
        truth = json.load(open(truth_path))
        if truth.get("environment"):
            truth["environment"]["file"] = os.path.abspath(
                os.path.join(folder, truth["environment"]["file"]))
        shutil.copytree(folder, key + ".tmp", dirs_exist_ok=True)
        with open(os.path.join(key + ".tmp", "truth.json"), "w") as f:
            json.dump(truth, f, indent=1)
        os.replace(key + ".tmp", key)


def environment_options(path, lights, rotation):
    """synth's --environment options (rotation: None for synth's default, or
    its --environment-rotation text)."""
    out = ["--environment", os.path.abspath(path), "--environment-lights", str(lights)]
    return out + (["--environment-rotation", rotation] if rotation else [])


def add_scene_arguments(p, renderer, map_use):
    """The options blender_fidelity.py and threejs_fidelity.py share: the scene,
    the flash or the map (map_use: what the renderer makes of it), synth's
    cache, the check's bound and the orientation check."""
    p.add_argument("--size", default="320x240")
    p.add_argument("--supersample", type=int, default=4)
    p.add_argument("--flash-offset", default="2.5,-1.5,0")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--max-rmse", type=float)
    p.add_argument("--environment", help="an equirectangular EXR: the map's median-cut lights "
                                         "in clayfit, " + map_use)
    p.add_argument("--environment-lights", type=int, default=1024)
    p.add_argument("--environment-rotation", help="synth's --environment-rotation")
    p.add_argument("--synth-cache", help="a folder keeping each clayfit synth, reused by a "
                                         "later run of the same command")
    p.add_argument("--rotation", help=f"9 numbers (rows): {renderer}'s map rotation instead of "
                                      "truth.json's (to show a wrong one fails)")
    p.add_argument("--orientation", type=float, metavar="DEGREES",
                   help="instead of the comparison, the orientation check of a Lambert sphere "
                        "under a one-patch map: both images lit from the patch within DEGREES")


def synth_scene(a, fit, folder, prog):
    """clayfit's rendering of the scene the parsed options a (add_scene_arguments)
    describe, for fit, into folder; its seconds."""
    t0 = time.monotonic()
    environment = environment_options(a.environment, a.environment_lights,
                                      a.environment_rotation) if a.environment else None
    synth_fit(a.clayfit, fit, folder, a.size, a.supersample, a.flash_offset, prog, environment,
              a.synth_cache)
    return time.monotonic() - t0


# --- the environment map's frame ----------------------------------------------

def map_direction(width, height, x, y):
    """clayfit's equirectangular convention (src/capture/envmap.h), map frame
    y up: the direction of pixel (x, y) (column, row from the top; centres
    at integer + 0.5 are x + 0.5 here)."""
    theta = math.pi * (y + 0.5) / height
    phi = 2.0 * math.pi * (x + 0.5) / width
    return [-math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]


def map_pixel(width, height, d):
    """The inverse of map_direction: (x, y) of a unit map-frame direction."""
    theta = math.acos(max(-1.0, min(1.0, d[1])))
    phi = math.atan2(-d[2], -d[0]) % (2.0 * math.pi)
    return phi / (2.0 * math.pi) * width - 0.5, theta / math.pi * height - 0.5


# Cycles' equirectangular lookup (intern/cycles/util/math_... direction_to_equirectangular,
# range (-2 pi, pi, -pi, pi)): u = 1/2 - atan2(D.y, D.x)/(2 pi), v = 1 - acos(D.z)/pi with v
# up from the bottom row. With clayfit's theta = pi (1 - v) and phi = 2 pi u, Cycles' D
# reads the texel of map direction d where D = (d.x, -d.z, d.y): this rotation (synth's
# default, the map's up to Blender's +z).
CYCLES_FROM_MAP = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]


# three.js' equirectangular lookup (equirectUv in common.glsl, the map's rows bottom first as
# EXRLoader stores them): u = atan2(e.z, e.x)/(2 pi) + 1/2, v = asin(e.y)/pi + 1/2 for the
# direction e in the environment's frame: clayfit's own (src/capture/envmap.h), e = d.
THREE_FROM_MAP = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def truth_environment(folder):
    """truth.json's environment (synth --environment; data_schema/truth.schema.json): the
    map's path, its light count K and the rotation (3 x 3 rows, map frame to world);
    None for a flash capture."""
    truth = json.load(open(os.path.join(folder, "truth.json")))
    env = truth.get("environment")
    if not env:
        return None
    rot = env["rotation"]
    return {"path": os.path.join(folder, env["file"]), "lights": env["count"],
            "rotation": [rot[0:3], rot[3:6], rot[6:9]]}


def lambert_light_direction(values, coverage, camera, w, h, stride):
    """The direction of the one light that best explains a Lambert sphere
    (unit, at the origin): over the lit pixels (above 5 % of the peak; the
    mask covers them fully) the value is n . g with n the pixel centre's
    normal, g = rho E l; least squares for g, returned normalised. Any
    renderer's image gives it, noise and all: the orientation check."""
    r, c = camera["r"], camera["centre"]
    lum = [sum(values[stride * i + k] for k in range(3)) / 3.0 for i in range(w * h)]
    peak = max(lum[i] for i in range(w * h) if coverage[i] >= 1.0 - 1e-6)
    a = [[0.0] * 3 for _ in range(3)]
    rhs = [0.0] * 3
    for i in range(w * h):
        if coverage[i] < 1.0 - 1e-6 or lum[i] < 0.05 * peak:
            continue
        xc = ((i % w) + 0.5 - camera["cx"]) / camera["fx"]
        yc = ((i // w) + 0.5 - camera["cy"]) / camera["fy"]
        ray = [r[0][j] * xc + r[1][j] * yc + r[2][j] for j in range(3)]
        norm = math.sqrt(sum(v * v for v in ray))
        ray = [v / norm for v in ray]
        b = sum(ray[j] * c[j] for j in range(3))
        disc = b * b - (sum(v * v for v in c) - 1.0)
        if disc <= 0.0:
            continue
        t = -b - math.sqrt(disc)
        n = [c[j] + t * ray[j] for j in range(3)]
        for p in range(3):
            rhs[p] += n[p] * lum[i]
            for q in range(3):
                a[p][q] += n[p] * n[q]
    g = solve3(a, rhs)
    norm = math.sqrt(sum(v * v for v in g))
    return [v / norm for v in g]


def map_mean_direction(path, prog):
    """The map's energy-weighted mean direction in its own frame (the
    direction of median cut's K = 1 light): sum of luminance dw d."""
    info = run(["oiiotool", "--info", path], "oiiotool --info", prog)
    m = re.search(r"(\d+) x\s+(\d+)", info)
    width, height = int(m.group(1)), int(m.group(2))
    values = exr_values(path, 3, prog)
    g = [0.0, 0.0, 0.0]
    for y in range(height):
        weight = math.sin(math.pi * (y + 0.5) / height)
        for x in range(width):
            i = 3 * (y * width + x)
            lum = 0.2126 * values[i] + 0.7152 * values[i + 1] + 0.0722 * values[i + 2]
            d = map_direction(width, height, x, y)
            for k in range(3):
                g[k] += lum * weight * d[k]
    norm = math.sqrt(sum(v * v for v in g))
    return [v / norm for v in g]


def orientation(values, coverage, folder, w, h, stride, prog):
    """The orientation check of a Lambert sphere lit by a map with one bright
    patch (docs/fidelity.md, "HDRI rows"): the angle in degrees between the
    light direction the image shows (lambert_light_direction) and where
    truth.json's rotation puts the patch in the world; also both directions."""
    env = truth_environment(folder)
    d = map_mean_direction(env["path"], prog)
    rot = env["rotation"]
    expected = [sum(rot[i][k] * d[k] for k in range(3)) for i in range(3)]
    seen = lambert_light_direction(values, coverage, colmap_camera(folder), w, h, stride)
    dot = max(-1.0, min(1.0, sum(seen[k] * expected[k] for k in range(3))))
    return math.degrees(math.acos(dot)), seen, expected


def report_orientation(name, renderer, c, b, coverage, folder, w, h, stride, max_deg, prog):
    """The orientation check of clayfit's image c and the renderer's b: one
    JSON line each; True (and a FAIL line) when either is off by more than
    max_deg."""
    failed = False
    for who, values in (("clayfit", c), (renderer, b)):
        angle, seen, expected = orientation(values, coverage, folder, w, h, stride, prog)
        print(json.dumps({"fit": name, "image": who, "orientation_error_deg": angle,
                          "light_seen": seen, "light_expected": expected}))
        if not angle <= max_deg:
            print(f"FAIL: orientation: {who}'s sphere is lit from {angle:.1f} degrees off the "
                  f"map's bright patch (limit {max_deg:g})")
            failed = True
    return failed


def solve3(a, b):
    """a x = b for a 3 x 3 system (Cramer's rule; a is a normal matrix here)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    out = []
    for k in range(3):
        m = [row[:] for row in a]
        for i in range(3):
            m[i][k] = b[i]
        out.append(det(m) / d)
    return out


def _records(path):
    return [line for line in open(path).read().split("\n") if line and not line.startswith("#")]


def rotation(q):
    """COLMAP's world-to-camera rotation (rows) of a unit quaternion (qw, qx, qy, qz)."""
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def camera_centre(q, t):
    """The camera's centre in the world, −Rᵀ t, of COLMAP's pose (q, t)."""
    r = rotation(q)
    return [-sum(r[k][i] * t[k] for k in range(3)) for i in range(3)]


def colmap_camera(folder):
    """Camera 0 of a synth capture's sparse/0 text model: PINHOLE intrinsics,
    the world-to-camera rotation r (rows) and the centre in the world."""
    cam = _records(os.path.join(folder, "sparse/0/cameras.txt"))[0].split()
    if cam[1] != "PINHOLE":
        raise SystemExit(f"scene_compare: {folder}: camera model {cam[1]}, expected PINHOLE")
    fx, fy, cx, cy = map(float, cam[4:8])
    img = _records(os.path.join(folder, "sparse/0/images.txt"))[0].split()
    pose = [float(x) for x in img[1:8]]
    r, centre = rotation(pose[:4]), camera_centre(pose[:4], pose[4:7])
    return {"fx": fx, "fy": fy, "cx": cx, "cy": cy, "r": r, "centre": centre}


def flash(folder, camera):
    """The flash of truth.json in the world (its offset is in camera
    coordinates) and its intensity."""
    truth = json.load(open(os.path.join(folder, "truth.json")))
    offset, r = truth["flash"]["offset"], camera["r"]
    position = [camera["centre"][i] + sum(r[k][i] * offset[k] for k in range(3))
                for i in range(3)]
    return position, truth["flash"]["intensity"]


def exr_values(path, channels, prog):
    """The first `channels` values of every pixel of an EXR, top row first,
    through oiiotool --dumpdata (no Python bindings needed)."""
    out = run(["oiiotool", "--dumpdata", path], "oiiotool --dumpdata", prog)
    pixels = {}
    for m in re.finditer(r"Pixel \((\d+), (\d+)\):((?: \S+)+)", out):
        pixels[(int(m.group(2)), int(m.group(1)))] = [float(v) for v in m.group(3).split()][:channels]
    return [v for key in sorted(pixels) for v in pixels[key]]


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


def compare(c, b, coverage, w, h, margin, stride, prog):
    """clayfit's c against the renderer's b (stride values a pixel, RGB first)
    over the pixels the mask covers fully (coverage: one value a pixel), at
    least `margin` pixels inside the silhouette. The relative RMSE is clayfit's
    (fit_residuals.c): sqrt(sum (b - c)^2 / sum c^2) over pixels and channels;
    also the ratio of the sums (a global gain) and the relative RMSE after the
    best gain (what is left is the shape). Returns the figures, the pixels
    compared and clayfit's mean value over them."""
    mask = erode([coverage[i] >= 1.0 - 1e-6 for i in range(w * h)], w, h, margin)
    inside = [i for i in range(w * h) if mask[i]]
    if not inside:
        raise SystemExit(f"{prog}: the mask leaves no pixel")
    bc = bb2 = sum_b = sum_c = peak = max_d = 0.0
    e2k, y2k = [0.0] * 3, [0.0] * 3
    for i in inside:
        for k in range(3):
            cv, bv = float(c[stride * i + k]), float(b[stride * i + k])
            if not (math.isfinite(cv) and math.isfinite(bv)):
                raise SystemExit(f"{prog}: pixel {i % w}, {i // w} is not finite")
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
    # sum (g b - c)^2 = g^2 sum b^2 - 2 g sum bc + sum c^2
    after = max(0.0, gain * gain * bb2 - 2.0 * gain * bc + y2)
    result = {"pixels": len(inside), "relative_rmse": math.sqrt(e2 / y2),
              "sum_ratio": sum_b / sum_c, "relative_rmse_after_gain": math.sqrt(after / y2),
              "relative_rmse_per_channel": [math.sqrt(e2k[k] / y2k[k]) for k in range(3)],
              "max_abs_diff_over_peak": max_d / peak}
    return result, inside, sum_c / (3 * len(inside))


def diff_values(c, b, inside, w, h, mean, stride):
    """The difference image, RGB in [0, 1] (3 values a pixel, in c's pixel
    order): (b - c) as grey 0.5 +/- 0.5 at +/- 25 % of clayfit's mean value
    (each channel apart), black outside the compared pixels."""
    scale = 0.25 * mean
    img = [0.0] * (3 * w * h)
    for i in inside:
        for k in range(3):
            d = 0.5 + 0.5 * (b[stride * i + k] - c[stride * i + k]) / scale
            img[3 * i + k] = min(1.0, max(0.0, d))
    return img


def write_png(path, w, h, rgb):
    """An 8-bit RGB PNG of values in [0, 1], top row first (zlib only)."""
    raw = b"".join(b"\0" + bytes(int(round(255 * v)) for v in rgb[3 * w * y:3 * w * (y + 1)])
                   for y in range(h))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def report(r, max_rmse):
    """One fit's JSON line and Markdown row; True when its relative RMSE is
    above max_rmse (when given)."""
    print(json.dumps(r))
    print(f"| {r['fit']} | {100 * r['relative_rmse']:.2f} % | {r['sum_ratio']:.4f} | "
          f"{100 * r['relative_rmse_after_gain']:.2f} % | {r['pixels']} |")
    if max_rmse is not None and not r["relative_rmse"] <= max_rmse:
        print(f"FAIL: {r['fit']}: relative RMSE {r['relative_rmse']:.4g} is above "
              f"{max_rmse:.4g}")
        return True
    return False


# --- three.js in headless Chromium -------------------------------------------

# The page's camera: a THREE.PerspectiveCamera with colmap_camera()'s pose
# (COLMAP's x right, y down, z forward -> three.js' y up, z back) and its
# intrinsics (scaled by S for a supersampled target) as the projection.
CAMERA_JS = r"""
function colmapCamera(THREE, k, W, H, S) {
  const cam = new THREE.PerspectiveCamera(30, W / H, 0.1, 100);
  const r = k.r, c = k.centre;
  const basis = new THREE.Matrix4().makeBasis(new THREE.Vector3(r[0][0], r[0][1], r[0][2]),
    new THREE.Vector3(-r[1][0], -r[1][1], -r[1][2]), new THREE.Vector3(-r[2][0], -r[2][1], -r[2][2]));
  cam.quaternion.setFromRotationMatrix(basis);
  cam.position.set(c[0], c[1], c[2]);
  cam.updateMatrixWorld(true);
  const n = 0.1, f = 100;
  const fx = k.fx * S, fy = k.fy * S, cx = k.cx * S, cy = k.cy * S;
  cam.projectionMatrix.set(2 * fx / W, 0, 1 - 2 * cx / W, 0,
                           0, 2 * fy / H, 2 * cy / H - 1, 0,
                           0, 0, -(f + n) / (f - n), -2 * f * n / (f - n),
                           0, 0, -1, 0);
  cam.projectionMatrixInverse.copy(cam.projectionMatrix).invert();
  return cam;
}

// a WebGL2 renderer with float render targets, linear output
function floatRenderer(THREE, canvas) {
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  const gl = renderer.getContext();
  if (!(gl instanceof WebGL2RenderingContext)) throw new Error('no WebGL2');
  if (!gl.getExtension('EXT_color_buffer_float')) throw new Error('no EXT_color_buffer_float');
  renderer.setPixelRatio(1);
  return renderer;
}

function floatTarget(THREE, W, H) {
  return new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType,
    format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    depthBuffer: true });
}

// the scene rendered into the float target: its RGBA, GL's rows (bottom first)
function renderFloat(THREE, renderer, target, world, cam, W, H) {
  renderer.setRenderTarget(target);
  renderer.setClearColor(0x000000, 0);
  renderer.clear();
  renderer.render(world, cam);
  const pixels = new Float32Array(W * H * 4);
  renderer.readRenderTargetPixels(target, 0, 0, W, H, pixels);
  return pixels;
}

// a Float32Array as base64 (the page's result travels in the DOM)
function base64Floats(values) {
  const bytes = new Uint8Array(values.buffer);
  let text = '';
  for (let i = 0; i < bytes.length; i += 8192)
    text += String.fromCharCode.apply(null, bytes.subarray(i, i + 8192));
  return btoa(text);
}
"""


def chromium_skip(node_modules):
    """(browser, None), or (None, the reason to skip: exit 77)."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if not browser:
        return None, "SKIP: no Chromium (apt-get install chromium)"
    for need in ("three/package.json", ".bin/esbuild"):
        if not os.path.exists(os.path.join(node_modules, need)):
            return None, f"SKIP: no {need} in {node_modules} (scripts/install-deps.sh installs it)"
    if not shutil.which("oiiotool"):
        return None, "SKIP: no oiiotool"
    return browser, None


def build_page(work, node_modules, script, prog):
    """WORK/index.html running `script` (an ES module importing 'three', with
    CAMERA_JS's functions in scope), bundled into a classic script by esbuild
    (Chromium refuses ES modules from file://)."""
    entry = os.path.join(work, "entry.js")
    with open(entry, "w") as f:
        f.write(script + CAMERA_JS)
    env = dict(os.environ, NODE_PATH=node_modules)
    esbuild = os.path.join(node_modules, ".bin", "esbuild")
    run([esbuild, entry, "--bundle", "--format=iife", "--log-level=warning",
         "--outfile=" + os.path.join(work, "bundle.js")], "esbuild", prog, env=env)
    page = os.path.join(work, "index.html")
    with open(page, "w") as f:
        f.write('<!doctype html><html><body><pre id="out">PENDING</pre>'
                '<script src="bundle.js"></script></body></html>')
    return page


def run_chromium(browser, page, budget_ms, timeout, prog):
    """The JSON the page writes into #out as 'RESULT json END' (or 'ERROR
    message END'), read back with --dump-dom."""
    cmd = [browser, "--headless", "--no-sandbox", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--hide-scrollbars",
           f"--virtual-time-budget={budget_ms}", "--dump-dom", "file://" + page]
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    m = re.search(r"(RESULT|ERROR) (.*?) END", dom.stdout, re.S)
    if not m:
        raise SystemExit(f"{prog}: the page did not finish: " + dom.stderr[-2000:])
    if m.group(1) == "ERROR":
        raise SystemExit(f"{prog}: the page failed: " + m.group(2))
    return json.loads(m.group(2))
