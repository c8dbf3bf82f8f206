#!/usr/bin/env python3
"""Captures whose directional lights have unknown, equal intensities.

usage: check_lights.py equal CLAYFIT WORKDIR
       check_lights.py uw CLAYFIT DATADIR WORKDIR
       check_lights.py bad CLAYFIT WORKDIR
       check_lights.py colmap CLAYFIT WORKDIR
       check_lights.py bomb CLAYFIT WORKDIR [--no-limit]
       check_lights.py probe_bad CLAYFIT WORKDIR

equal: a small orthographic capture (a Lambertian sphere under 6 directional
lights of irradiance 1.25, 16-bit linear PNG) declared once with
"intensities": "equal" and once with a file of rows '1 1 1'. Both load as
relative radiometry (clayfit inspect), both fit (M0) with a relative RMSE
under 1e-3 and the albedo in the lights' relative units (1.25 x the truth),
to the same numbers; "equal" with "radiometry": "absolute" is refused
(exit 2, naming the field).

uw: clayfit lights on ../shared/data/uw_chrome (12 photos, mask), then a
capture of those photos whose light is the directions file written, with
"intensities": "equal": clayfit inspect loads it, and reports the 12
directions as written. Exit 77 without the data.

bad: clayfit lights on chrome balls drawn here (a disc of radius 30 px with
highlights of radius 2 px where the lights' mirror points are): no
highlight, two where one was expected (and accepted with --lights 2), a
ball clipped by the border, a highlight of radius 12 px (16 % of the ball:
said so, not "no highlight ... is not 8 times its background") are errors
(exit 2, nothing written); a light behind the ball (150 degrees from the
view) is a warning in lights.json.

colmap: a chrome ball seen through a PINHOLE camera of a COLMAP text model
whose pose turns 30 degrees about y, drawn here (one sample a pixel, a light
6 degrees across): the direction written is the light's in the model's
world frame (R^T of the camera frame's), within 1.5 degrees (the library's
accuracy is test_chrome_ball's; this checks the frame and the model's
look-up), found under the name given with --image; one mask for two photos
of different poses is refused.

bomb: photos whose PNG header declares 26000 x 26000 (the pixel data of a
96 x 80 one): refused from the header, before decoding, against the mask's
size and against the other photos' with --silhouette, under an address-space
limit of 2 GB that decoding (2.7 GB of floats) exceeds (--no-limit: without
it, for the sanitizers, which reserve terabytes); the cap on decoded bytes
(--max-image-memory) from the headers. Exit 2, nothing written.

probe_bad: clayfit lights --probe on a 96 x 80 PFM ball: a reflectance or an
exposure out of range (1e-300 made infinite texels, 1e306 an all-zero map),
photo values that overflow a float over the reflectance 0.5, a black ball,
a photo declaring 16000 x 16000 beside a 96 x 80 mask (refused from the
headers, before decoding), the cap on decoded bytes. Exit 2, no map written.
"""
import json
import math
import os
import re
import resource
import shutil
import struct
import subprocess
import sys
import zlib

WIDTH, HEIGHT = 96, 80
CX, CY, RADIUS = 48.0, 40.0, 30.0
ALBEDO = (0.6, 0.45, 0.3)
IRRADIANCE = 1.25
LIGHTS = [(0, 0, 1), (0.5, 0.2, 0.84), (-0.4, 0.4, 0.82), (0.1, -0.6, 0.79),
          (-0.5, -0.3, 0.81), (0.6, -0.1, 0.79)]


def png(path, width, height, channels, depth, value):
    """A PNG of value(x, y) -> list of channel values in [0, 1]."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    top = (1 << depth) - 1
    rows = []
    for y in range(height):
        row = bytearray(b"\x00")
        for x in range(width):
            for v in value(x, y):
                code = max(0, min(top, round(v * top)))
                row += code.to_bytes(depth // 8, "big")
        rows.append(bytes(row))
    kind = {1: 0, 3: 2}[channels]
    header = struct.pack(">IIBBBBB", width, height, depth, kind, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                chunk(b"IDAT", zlib.compress(b"".join(rows))) + chunk(b"IEND", b""))


def normal(x, y):
    nx, ny = (x + 0.5 - CX) / RADIUS, -(y + 0.5 - CY) / RADIUS
    q = nx * nx + ny * ny
    return None if q > 1.0 else (nx, ny, math.sqrt(1.0 - q))


def lambert(light):
    length = math.sqrt(sum(c * c for c in light))
    l = [c / length for c in light]

    def value(x, y):
        n = normal(x, y)
        if n is None:
            return (0.0, 0.0, 0.0)
        cosine = max(0.0, sum(a * b for a, b in zip(n, l)))
        return tuple(a / math.pi * IRRADIANCE * cosine for a in ALBEDO)
    return value


SCHEMA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "data_schema",
                      "lights.schema.json")


def load_report(path):
    """lights.json, validated against data_schema/lights.schema.json."""
    import jsonschema
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    with open(SCHEMA, encoding="utf-8") as f:
        jsonschema.validate(doc, json.load(f))
    return doc


def run(command):
    return subprocess.run(command, capture_output=True, text=True, timeout=600)


def fail(message):
    print("FAIL:", message)
    return 1


def capture(files, directions, intensities, radiometry=None):
    doc = {
        "clayfit_capture": 1,
        "camera": {"type": "orthographic", "view": [0, 0, 1]},
        "images": {"files": files, "mask": "mask.png"},
        "colour": {"encoding": "linear"},
        "geometry": {"type": "sphere_from_silhouettes", "margin_px": 1},
        "lights": [{"type": "directional_per_image", "directions": directions,
                    "intensities": intensities}],
    }
    if radiometry:
        doc["radiometry"] = radiometry
    return doc


def write_json(path, doc):
    with open(path, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=2)


def equal(clayfit, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    files = []
    for k, light in enumerate(LIGHTS):
        files.append(f"photo{k}.png")
        png(os.path.join(work, files[-1]), WIDTH, HEIGHT, 3, 16, lambert(light))
    png(os.path.join(work, "mask.png"), WIDTH, HEIGHT, 1, 8,
        lambda x, y: (1.0 if normal(x, y) else 0.0,))
    with open(os.path.join(work, "directions.txt"), "w", encoding="utf-8") as f:
        f.writelines(f"{x} {y} {z}\n" for x, y, z in LIGHTS)
    with open(os.path.join(work, "ones.txt"), "w", encoding="utf-8") as f:
        f.writelines("1 1 1\n" for _ in LIGHTS)
    write_json(os.path.join(work, "equal.json"), capture(files, "directions.txt", "equal"))
    write_json(os.path.join(work, "ones.json"),
               capture(files, "directions.txt", "ones.txt", "relative"))
    write_json(os.path.join(work, "absolute.json"),
               capture(files, "directions.txt", "equal", "absolute"))
    failures = 0
    result = run([clayfit, "--quiet", "inspect", "--json", os.path.join(work, "equal.json")])
    if result.returncode != 0:
        return fail(f"inspect equal.json: exit {result.returncode}: {result.stderr}")
    summary = json.loads(result.stdout)
    if summary["radiometry"] != "relative":
        failures += fail(f"radiometry {summary['radiometry']}, expected relative")
    params = {}
    for name in ("equal", "ones"):
        out = os.path.join(work, "fit_" + name)
        result = run([clayfit, "--quiet", "fit", os.path.join(work, name + ".json"), "-o", out,
                      "--model", "M0", "--footprint", "centre"])
        if result.returncode != 0:
            return fail(f"fit {name}: exit {result.returncode}: {result.stderr}")
        with open(os.path.join(out, "fit.json"), encoding="utf-8") as f:
            fit = json.load(f)
        params[name] = fit["params"]["albedo"]["value"]
        rmse = fit["residuals"]["relative_rmse"]
        print(f"{name}: albedo {params[name]}, relative RMSE {rmse:.2e}")
        if not rmse < 1e-3:
            failures += fail(f"{name}: relative RMSE {rmse}")
        for c in range(3):
            if abs(params[name][c] / (ALBEDO[c] * IRRADIANCE) - 1) > 2e-3:
                failures += fail(f"{name}: albedo[{c}] {params[name][c]}, expected "
                                 f"{ALBEDO[c] * IRRADIANCE} ({IRRADIANCE} x {ALBEDO[c]})")
    if any(abs(a - b) > 1e-9 * abs(b) for a, b in zip(params["equal"], params["ones"])):
        failures += fail(f"equal {params['equal']} != ones {params['ones']}")
    result = run([clayfit, "--quiet", "inspect", os.path.join(work, "absolute.json")])
    if result.returncode != 2 or "lights[0].intensities" not in result.stderr or \
            "relative" not in result.stderr:
        failures += fail(f"absolute + equal: exit {result.returncode}, {result.stderr!r}")
    return failures


def uw(clayfit, data, work):
    chrome = os.path.join(data, "uw_chrome")
    if not os.path.isfile(os.path.join(chrome, "chrome.mask.png")):
        print(f"skipped: {chrome} is absent")
        return 77
    shutil.rmtree(work, ignore_errors=True)
    photos = [os.path.join(chrome, f"chrome.{k}.png") for k in range(12)]
    result = run([clayfit, "--quiet", "lights", *photos, "--mask",
                  os.path.join(chrome, "chrome.mask.png"), "-o", work])
    if result.returncode != 0:
        return fail(f"lights: exit {result.returncode}: {result.stderr}")
    report = load_report(os.path.join(work, "lights.json"))
    rows = []
    with open(os.path.join(work, "directions.txt"), encoding="utf-8") as f:
        rows = [[float(v) for v in line.split()] for line in f if not line.startswith("#")]
    failures = 0
    if len(rows) != 12 or len(report["images"]) != 12:
        failures += fail(f"{len(rows)} rows, {len(report['images'])} images")
    for k, row in enumerate(rows):
        if abs(math.hypot(*row) - 1) > 1e-9 or row[2] <= 0:
            failures += fail(f"row {k}: {row} is not a unit vector toward the camera")
        light = report["images"][k]["lights"][0]
        if light["warnings"] or max(light["per_px_deg"].values()) > 1.5:
            failures += fail(f"image {k}: {light}")
    doc = capture(photos, "directions.txt", "equal")
    doc["images"]["mask"] = os.path.join(chrome, "chrome.mask.png")
    doc["colour"] = {"encoding": "srgb"}
    doc["lights"] = report["capture_lights"]
    write_json(os.path.join(work, "capture.json"), doc)
    result = run([clayfit, "--quiet", "inspect", "--json", os.path.join(work, "capture.json")])
    if result.returncode != 0:
        return fail(f"inspect: exit {result.returncode}: {result.stderr}")
    summary = json.loads(result.stdout)
    if summary["radiometry"] != "relative" or len(summary["images"]) != 12:
        failures += fail(f"inspect: radiometry {summary['radiometry']}, "
                         f"{len(summary['images'])} images")
    print(f"uw_chrome: 12 directions written and loaded; first {rows[0]}")
    return failures


def chrome(path, lights, cx=CX, spot=2.0):
    """An 8-bit chrome ball: dim, with a bright disc of radius `spot` px at
    each light's mirror point (the normal halfway between the light and the
    view)."""
    points = []
    for light in lights:
        h = [a + b for a, b in zip(light, (0, 0, 1))]
        length = math.sqrt(sum(c * c for c in h))
        points.append((cx + RADIUS * h[0] / length, CY - RADIUS * h[1] / length))

    def value(x, y):
        if (x + 0.5 - cx) ** 2 + (y + 0.5 - CY) ** 2 > RADIUS ** 2:
            return (0.02,)
        bright = any((x + 0.5 - px) ** 2 + (y + 0.5 - py) ** 2 <= spot ** 2 for px, py in points)
        return (1.0 if bright else 0.06,)
    png(path, WIDTH, HEIGHT, 1, 8, value)
    png(path.replace(".png", ".mask.png"), WIDTH, HEIGHT, 1, 8,
        lambda x, y: (1.0 if (x + 0.5 - cx) ** 2 + (y + 0.5 - CY) ** 2 <= RADIUS ** 2 else 0.0,))


def bad(clayfit, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    behind = (math.sin(math.radians(150)), 0.0, math.cos(math.radians(150)))
    cases = [  # name, lights drawn, disc centre x, extra options, exit, stderr or warning
        ("none", [], CX, [], 2, "no highlight on the ball"),
        ("wide", [(0, 0, 1)], CX, [], 2,
         "wide.png: no highlight on the ball: its bright region \\(at least 0.5 times its "
         "brightest value 1\\) covers 16 % of the ball, more than the 10 % a chrome ball's "
         "highlight can cover \\(an overexposed photo, or a ball that is not a mirror\\?\\); "
         "take a shorter exposure"),
        ("two", [(0.3, 0.3, 0.9), (-0.4, -0.2, 0.89)], CX, [], 2,
         "2 highlights on the ball .* where 1 was expected"),
        ("two_declared", [(0.3, 0.3, 0.9), (-0.4, -0.2, 0.89)], CX, ["--lights", "2"], 0, None),
        ("clipped", [(0.3, 0.3, 0.9)], 20.0, [], 2, "touches the image border"),
        ("behind", [behind], CX, [], 0, "grazing"),
    ]
    failures = 0
    for name, lights, cx, options, status, expected in cases:
        photo = os.path.join(work, name + ".png")
        chrome(photo, lights, cx, 12.0 if name == "wide" else 2.0)
        out = os.path.join(work, "out_" + name)
        result = run([clayfit, "--quiet", "lights", photo, "--mask",
                      photo.replace(".png", ".mask.png"), "-o", out, *options])
        written = os.path.exists(os.path.join(out, "lights.json"))
        if result.returncode != status or written != (status == 0):
            failures += fail(f"{name}: exit {result.returncode} (expected {status}), "
                             f"lights.json written: {written}; {result.stderr}")
            continue
        if status != 0:
            if not re.search(expected, result.stderr):
                failures += fail(f"{name}: stderr {result.stderr!r} lacks /{expected}/")
            continue
        report = load_report(os.path.join(out, "lights.json"))
        found = report["images"][0]["lights"]
        if len(found) != len(lights):
            failures += fail(f"{name}: {len(found)} lights")
        warnings = " ".join(w for light in found for w in light["warnings"])
        if (expected or "") not in warnings or (not expected and "grazing" in warnings):
            failures += fail(f"{name}: warnings {warnings!r}")
        print(f"{name}: {[light['direction'] for light in found]} {warnings}")
    return failures


def refused(name, command, expected, output, limit=None):
    """1 if command does not exit 2 with stderr matching `expected`, or
    writes `output`; limit: an address-space limit in bytes."""
    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    result = subprocess.run(command, capture_output=True, text=True, timeout=600,
                            preexec_fn=limited if limit else None)
    if result.returncode != 2 or not re.search(expected, result.stderr):
        return fail(f"{name}: exit {result.returncode}, stderr {result.stderr!r}; expected "
                    f"exit 2 and /{expected}/")
    if os.path.exists(output):
        return fail(f"{name}: {output} was written")
    print(f"{name}: {result.stderr.strip()}")
    return 0


def bomb_photo(path, width, height):
    """A chrome ball photo whose PNG header declares width x height."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "capture"))
    from make_hostile_captures import patch_png_size
    chrome(path, [(0.3, 0.3, 0.9)])
    patch_png_size(path, width, height)


def bomb(clayfit, work, limit):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    photo, huge = os.path.join(work, "photo.png"), os.path.join(work, "huge.png")
    chrome(photo, [(0.3, 0.3, 0.9)])
    bomb_photo(huge, 26000, 26000)
    mask, out = photo.replace(".png", ".mask.png"), os.path.join(work, "out")
    written = os.path.join(out, "lights.json")
    before = "\\(from its header, before decoding\\)"
    return (refused("mask", [clayfit, "--quiet", "lights", huge, "--mask", mask, "-o", out],
                    f"huge.png is 26000 x 26000 pixels but its mask .*photo.mask.png is 96 x 80 "
                    f"{before}", written, limit) +
            refused("silhouette", [clayfit, "--quiet", "lights", photo, huge, "--silhouette",
                                   "-o", out],
                    f"huge.png is 26000 x 26000, .*photo.png is 96 x 80: one outline cannot serve "
                    f"both {before}", written, limit) +
            refused("cap", [clayfit, "--quiet", "lights", photo, "--mask", mask, "-o", out,
                            "--max-image-memory", "1e-5"],
                    "photo.png \\(96 x 80 x 1\\): the photos and masks up to it decode to "
                    "3.07e-05 GB of 32-bit floats, more than the cap of 1e-05 GB \\(checked from "
                    "the headers, before decoding", written))


def pfm(path, value):
    """A 96 x 80 RGB PFM (little-endian, bottom row first) of value(x, y)."""
    rows = [b"".join(struct.pack("<3f", *([value(x, y)] * 3)) for x in range(WIDTH))
            for y in reversed(range(HEIGHT))]
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (WIDTH, HEIGHT) + b"".join(rows))


def probe_bad(clayfit, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)

    def on_ball(level):
        return lambda x, y: level if (x + 0.5 - CX) ** 2 + (y + 0.5 - CY) ** 2 <= RADIUS ** 2 \
            else 0.0
    for name, level in (("ball", 0.5), ("huge", 3e38), ("black", 0.0)):
        pfm(os.path.join(work, name + ".pfm"), on_ball(level))
    chrome(os.path.join(work, "photo.png"), [(0.3, 0.3, 0.9)])
    bomb_photo(os.path.join(work, "bomb.png"), 16000, 16000)
    out = os.path.join(work, "probe.exr")
    circle = ["--circle", str(CX), str(CY), str(RADIUS), "-o", out]

    def probe(photo, *options):
        return [clayfit, "lights", "--probe", os.path.join(work, photo), *options]
    cases = [
        ("reflectance", probe("ball.pfm", "--reflectance", "1e-300", *circle),
         "--reflectance: 1e-300 is outside \\[0.01, 1\\]"),
        ("exposure", probe("ball.pfm", "--exposures", "1e306", *circle),
         "--exposures: exposure 1e\\+306 is outside \\[1e-09, 1e\\+09\\]"),
        ("overflow", probe("huge.pfm", "--reflectance", "0.5", *circle),
         "light probe: [0-9]+ texels of the map are not finite .*over the reflectance 0.5 is "
         "beyond a float's range"),
        ("black", probe("black.pfm", *circle),
         "light probe: the map is black \\(its brightest value 0 is below a float's smallest "
         "normal value"),
        ("bomb", probe("bomb.png", "--mask", os.path.join(work, "photo.mask.png"), "-o", out),
         "photo.mask.png is 96 x 80 pixels but .*bomb.png is 16000 x 16000: the mask must be the "
         "photo's size \\(from its header, before decoding\\)"),
        ("cap", probe("ball.pfm", "--max-image-memory", "1e-5", *circle),
         "ball.pfm \\(96 x 80 x 3\\): the photos and masks up to it decode to 9.22e-05 GB of "
         "32-bit floats, more than the cap of 1e-05 GB"),
    ]
    failures = sum(refused(name, command, expected, out) for name, command, expected in cases)
    # the inputs of those cases within range give a map
    result = run(probe("ball.pfm", "--reflectance", "0.01", "--exposures", "1e9", *circle))
    if result.returncode != 0 or not os.path.exists(out):
        failures += fail(f"in range: exit {result.returncode}, {result.stderr!r}")
    return failures


def rotation(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def colmap(clayfit, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.join(work, "sparse"))
    width, height, f, u0, v0 = 320, 240, 400.0, 161.0, 119.5
    q = (math.cos(math.radians(15)), 0.0, math.sin(math.radians(15)), 0.0)
    R = rotation(q)
    centre, light_cam = (0.2, -0.1, 6.0), (0.3, -0.4, -0.85)
    n = math.sqrt(sum(c * c for c in light_cam))
    light_cam = [c / n for c in light_cam]
    light_world = [sum(R[i][j] * light_cam[i] for i in range(3)) for j in range(3)]  # R^T l
    cos_source = math.cos(math.radians(3.0))

    def hit(x, y):
        d = [(x + 0.5 - u0) / f, (y + 0.5 - v0) / f, 1.0]
        length = math.sqrt(sum(c * c for c in d))
        d = [c / length for c in d]
        dc = sum(a * b for a, b in zip(d, centre))
        disc = dc * dc - (sum(c * c for c in centre) - 1.0)
        if disc <= 0:
            return None
        t = dc - math.sqrt(disc)
        normal = [t * a - b for a, b in zip(d, centre)]
        dn = sum(a * b for a, b in zip(d, normal))
        return [a - 2 * dn * b for a, b in zip(d, normal)]

    def value(x, y):
        r = hit(x, y)
        if r is None:
            return (0.02,)
        return (1.0 if sum(a * b for a, b in zip(r, light_cam)) > cos_source else 0.06,)
    png(os.path.join(work, "ball.png"), width, height, 1, 8, value)
    png(os.path.join(work, "mask.png"), width, height, 1, 8,
        lambda x, y: (0.0 if hit(x, y) is None else 1.0,))
    sparse = os.path.join(work, "sparse")
    with open(os.path.join(sparse, "cameras.txt"), "w", encoding="utf-8") as f_:
        f_.write(f"1 PINHOLE {width} {height} {f} {f} {u0} {v0}\n")
    with open(os.path.join(sparse, "images.txt"), "w", encoding="utf-8") as f_:
        f_.write(f"7 {q[0]} {q[1]} {q[2]} {q[3]} 0.5 0.25 1.0 1 chrome_ball.jpg\n\n")
        f_.write(f"8 {q[0]} {q[1]} {q[2]} {q[3]} 0.5 0.25 2.0 1 moved.jpg\n\n")
    open(os.path.join(sparse, "points3D.txt"), "w", encoding="utf-8").close()
    out = os.path.join(work, "out")
    result = run([clayfit, "--quiet", "lights", os.path.join(work, "ball.png"), "--mask",
                  os.path.join(work, "mask.png"), "--colmap", sparse, "--image",
                  "chrome_ball.jpg", "-o", out])
    if result.returncode != 0:
        return fail(f"lights --colmap: exit {result.returncode}: {result.stderr}")
    found = load_report(os.path.join(out, "lights.json"))["images"][0]["lights"][0]["direction"]
    angle = math.degrees(math.acos(min(1.0, sum(a * b for a, b in zip(found, light_world)))))
    print(f"colmap: found {found}, light {light_world}: {angle:.3f} degrees apart")
    failures = 0 if angle < 1.5 else fail(f"colmap: {angle:.3f} degrees off")
    result = run([clayfit, "--quiet", "lights", os.path.join(work, "ball.png"), "--mask",
                  os.path.join(work, "mask.png"), "--colmap", sparse, "-o", out])
    if result.returncode != 2 or "no image 'ball.png' in the COLMAP model" not in result.stderr:
        failures += fail(f"colmap without --image: exit {result.returncode}, {result.stderr!r}")
    ball = os.path.join(work, "ball.png")
    result = run([clayfit, "--quiet", "lights", ball, ball, "--mask", os.path.join(work, "mask.png"),
                  "--colmap", sparse, "--image", "chrome_ball.jpg", "--image", "moved.jpg",
                  "-o", out])
    if result.returncode != 2 or "serves photos of one camera pose" not in result.stderr:
        failures += fail(f"one mask, two poses: exit {result.returncode}, {result.stderr!r}")
    return failures


def main():
    if sys.argv[1] == "equal":
        failures = equal(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "colmap":
        failures = colmap(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "bad":
        failures = bad(sys.argv[2], sys.argv[3])
    elif sys.argv[1] == "bomb":
        failures = bomb(sys.argv[2], sys.argv[3], None if "--no-limit" in sys.argv else 2 * 10**9)
    elif sys.argv[1] == "probe_bad":
        failures = probe_bad(sys.argv[2], sys.argv[3])
    else:
        failures = uw(sys.argv[2], sys.argv[3], sys.argv[4])
    if failures == 77:
        return 77
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
