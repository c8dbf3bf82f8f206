#!/usr/bin/env python3
"""Per-image gains (clayfit fit --fit-exposures; docs/fitting.md, Exposures).

usage: check_gains.py MODE CLAYFIT DIR
       check_gains.py diligent CLAYFIT DIR CAPTURE SHARED_DATA

  capture   DIR: a synthetic capture of M2, fitted with M2 (24 images, 320 x 240; the
            default pixel budget once dropped its last images' observations,
            and the fit failed: "does not constrain the fit ...").
  default   the default-budget fit of DIR with --fit-exposures finishes, and
            its gains (all truly 1) are 1 within 2 sd (as a set: within_2_sd),
            each with an sd > 0.
  recover   DIR's photos declared with wrong exposures ("exposure": "given",
            gains drawn at +-20 %, mean log 0): the fit with --fit-exposures
            finds the gains (1 / the declared exposure) within 2 sd, and its
            material equals the fit of the true capture (gains known) within
            2 sd; clayfit report lists each gain with its sd.
  refused   an orthographic capture of six images whose fourth is lit from
            behind (its gain moves nothing): --fit-exposures exits 2 before
            any fit, naming that image; and where it is lit at a grazing
            angle in noisy photos, its gain's predicted sd above 10 %.
  per-light a gain per light (--fit-gains per-light): the same fit as per image
            with one light per photo; with four lights in two photos each,
            each light's power found, its photos sharing its gain.
  several-lights  --fit-gains per-light where photos have two lights each,
            declared +15 % and -10 % off: each light's gain found within 2
            sd, the material that of the true intensities within 2 sd;
            refused (exit 2, no fit.json) where two lights share a direction
            in every photo and where one light lights every photo.
  white-balance  eight photos under lights of different colours: --fit-gains
            per-image-rgb finds each photo's red and blue gains against
            green, and fits far better than a gain per image.
  diligent  the DiLiGenT ball (tests/diligent_ball.capture.json; exit 77
            when SHARED_DATA/diligent_ball is absent), M4 under the default
            budget: with --fit-exposures it finishes (it failed: the budget's
            sample had no observation of the last images), 96 gains within
            20 % of 1 with an sd below 10 %, and the error without the
            highlight cores lower than without the gains.
"""
import json
import math
import os
import random
import shutil
import struct
import subprocess
import sys
import zlib


def run(clayfit, *args):
    """clayfit --quiet ARGS: (exit status, stderr)."""
    done = subprocess.run([clayfit, "--quiet", *args], capture_output=True, text=True)
    return done.returncode, done.stderr


def fit(clayfit, capture, out, *options):
    return fit_model(clayfit, capture, out, "M2", *options)


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    return ok


def make_capture(clayfit, out):
    shutil.rmtree(out, ignore_errors=True)
    status, stderr = run(clayfit, "synth", "-o", out, "--model", "M2", "--images", "24",
                         "--size", "320x240", "--seed", "5")
    if status != 0:
        sys.exit(f"clayfit synth: exit {status}: {stderr.strip()}")
    return True


def gains_of(doc):
    return [(i["exposure"], i["exposure_sd"]) for i in doc["residuals"]["per_image"]]


def default_budget(clayfit, folder):
    doc = fit(clayfit, os.path.join(folder, "capture.json"), os.path.join(folder, "default"),
              "--fit-exposures")
    gains = gains_of(doc)
    ok = check(doc["sample"]["observations"] < doc["sample"]["population"],
               "the default pixel budget was used")
    ok &= check(all(sd > 0 for _, sd in gains), "every gain has an sd > 0")
    ok &= within_2_sd([(e - 1) / sd for e, sd in gains], "the gains (truly 1)")
    return ok


def within_2_sd(z, what):
    """The gains' z-scores: within 2 sd as a set (each of 24 within 2 sd would
    happen by chance in only 0.95^24 = 29 % of captures): at most one in 20
    beyond 2 sd, none beyond 3, and their RMS below 1.5 (1 when the sds are
    right; above, they would be too small)."""
    z = [abs(v) for v in z]
    rms = math.sqrt(sum(v * v for v in z) / len(z))
    beyond = sum(v > 2 for v in z)
    return check(beyond <= len(z) // 20 and max(z) < 3 and rms < 1.5,
                 f"{what} within 2 sd: {beyond} of {len(z)} beyond 2 sd, worst {max(z):.2f} sd, "
                 f"RMS {rms:.2f} sd")


def material(doc):
    """(name, value, sd) of every fitted component."""
    out = []
    for name, p in doc["params"].items():
        values = p["value"] if isinstance(p["value"], list) else [p["value"]]
        sds = p["sd"] if isinstance(p["sd"], list) else [p["sd"]]
        for c, (v, s) in enumerate(zip(values, sds)):
            if s is not None and s > 0:
                out.append((f"{name}[{c}]", v, s))
    return out


def recover(clayfit, folder):
    with open(os.path.join(folder, "capture.json")) as f:
        capture = json.load(f)
    n = len(capture["images"]["files"])
    draw = random.Random(17)
    gains = [draw.uniform(0.8, 1.2) for _ in range(n)]
    mean_log = sum(math.log(g) for g in gains) / n
    exposures = [g / math.exp(mean_log) for g in gains]  # their mean log 0, as the fit's
    capture["images"]["exposures"] = exposures
    capture["colour"]["exposure"] = "given"
    wrong = os.path.join(folder, "wrong_exposures.json")
    with open(wrong, "w") as f:
        json.dump(capture, f, indent=1)
    # (every observation in both: the same data, only the gains' freedom between them)
    fitted = fit(clayfit, wrong, os.path.join(folder, "recover"), "--fit-exposures", "--budget",
                 "all")
    known = fit(clayfit, os.path.join(folder, "capture.json"), os.path.join(folder, "known"),
                "--budget", "all")
    ok = within_2_sd([(e - 1 / x) / sd for (e, sd), x in zip(gains_of(fitted), exposures)],
                     "the gains (1 / the declared exposure)")
    report = os.path.join(folder, "report")
    status, stderr = run(clayfit, "report", os.path.join(folder, "recover", "fit.json"), "-o",
                         report)
    ok &= check(status == 0, f"clayfit report: exit {status} {stderr.strip()}")
    if status == 0:
        with open(os.path.join(report, "index.html")) as f:
            page = f.read()
        first = gains_of(fitted)[0]
        ok &= check("<h2>Per-image gains</h2>" in page and
                    f"{first[0]:.4f} &plusmn; {first[1]:.4f}" in page,
                    "the report lists each gain with its sd")
    same = {name: value for name, value, _ in material(known)}
    for name, value, sd in material(fitted):
        if name in same:
            ok &= check(abs(value - same[name]) < 2 * sd,
                        f"{name}: {value:.6g} against {same[name]:.6g} with the gains known, "
                        f"{abs(value - same[name]) / sd:.2f} sd")
    return ok


def write_png(path, rows, channels=1):
    """An 8-bit greyscale (or, channels 3, RGB) PNG of rows (lists of 0..255,
    channels values a pixel)."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    raw = b"".join(b"\x00" + bytes(row) for row in rows)
    header = struct.pack(">IIBBBBB", len(rows[0]) // channels, len(rows), 8,
                         0 if channels == 1 else 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) +
                chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def sphere_photo(shade):
    """A 64 x 64 orthographic photo of a sphere (radius 26 px, background 5):
    shade(n) gives the channels' values at the unit normal n (0..1 of 200);
    and the sphere's mask."""
    size, cx, cy, radius = 64, 32.0, 32.0, 26.0
    rows, mask = [], []
    for y in range(size):
        row, mrow = [], []
        for x in range(size):
            nx, ny = (x + 0.5 - cx) / radius, -(y + 0.5 - cy) / radius
            r2 = nx * nx + ny * ny
            inside = r2 <= 1.0
            n = (nx, ny, math.sqrt(1.0 - r2) if inside else 0.0)
            row += [min(255, round(200 * v)) for v in shade(n)] if inside else [5] * len(shade(n))
            mrow.append(255 if inside else 0)
        rows.append(row)
        mask.append(mrow)
    return rows, mask


def facing(n, light):
    return max(0.0, n[0] * light[0] + n[1] * light[1] + n[2] * light[2])


def write_ortho_capture(folder, name, names, lights):
    """capture.json of an orthographic, linear 8-bit capture of the photos
    `names` (with mask.png) under `lights`; its path."""
    capture = {
        "clayfit_capture": 1,
        "name": name,
        "camera": {"type": "orthographic", "view": [0, 0, 1]},
        "images": {"files": names, "mask": "mask.png"},
        "colour": {"encoding": "linear"},
        "geometry": {"type": "sphere_from_silhouettes", "margin_px": 1},
        "lights": lights,
    }
    path = os.path.join(folder, "capture.json")
    with open(path, "w") as f:
        json.dump(capture, f, indent=1)
    return path


def ortho_capture(folder, lights, gains, name):
    """An orthographic capture of a Lambertian sphere (8-bit, linear), image k
    lit by the directional light lights[k] (a row each of the capture's
    directional_per_image files, irradiance 4) scaled by gains[k] (a number,
    or an RGB gain: the photos are then in colour)."""
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    names = []
    for k, (light, gain) in enumerate(zip(lights, gains)):
        rgb = gain if isinstance(gain, (list, tuple)) else [gain]
        rows, mask = sphere_photo(lambda n: [g * facing(n, light) for g in rgb])
        names.append(f"light{k + 1}.png")
        write_png(os.path.join(folder, names[-1]), rows, len(rgb))
    write_png(os.path.join(folder, "mask.png"), mask)
    with open(os.path.join(folder, "directions.txt"), "w") as f:
        f.writelines(f"{l[0]} {l[1]} {l[2]}\n" for l in lights)
    with open(os.path.join(folder, "intensities.txt"), "w") as f:
        f.writelines("4 4 4\n" for _ in lights)  # an albedo of 0.62
    return write_ortho_capture(folder, name, names, [
        {"type": "directional_per_image", "directions": "directions.txt",
         "intensities": "intensities.txt"}])


def refused(clayfit, folder):
    """Six photos, one light each; the fourth's light comes from behind, so
    that no visible point is lit and its gain moves nothing."""
    lights = [(0.0, 0.0, 1.0), (0.5, 0.0, 0.866), (-0.5, 0.0, 0.866), (0.0, 0.0, -1.0),
              (0.0, 0.5, 0.866), (0.0, -0.5, 0.866)]
    path = ortho_capture(folder, lights, [1.0] * 6, "six lights, the fourth behind the sphere")
    status, stderr = run(clayfit, "fit", path, "-o", os.path.join(folder, "fit"), "--model",
                         "M0", "--fit-exposures")
    print(stderr.strip())
    ok = check(status == 2, f"exit status 2 (bad input), got {status}")
    ok &= check("light4.png" in stderr and "light1.png" not in stderr,
                "the message names the fourth image, and only it")
    ok &= check(not os.path.exists(os.path.join(folder, "fit", "fit.json")), "no fit.json")
    # nearly so: the fourth lit from behind and the side, a thin crescent, in
    # photos with a noise of sd 0.5 (radiance up to 0.8): its gain's sd would
    # be 16 %, the others' 3 %
    lights[3] = (0.6, 0.0, -0.8)
    path = ortho_capture(os.path.join(folder, "crescent"), lights, [1.0] * 6,
                         "six lights, the fourth from behind and the side, noisy photos")
    with open(path) as f:
        capture = json.load(f)
    capture["noise"] = {"read": 0.5, "shot": 0.0}
    with open(path, "w") as f:
        json.dump(capture, f, indent=1)
    status, stderr = run(clayfit, "fit", path, "-o", os.path.join(folder, "crescent", "fit"),
                         "--model", "M0", "--fit-exposures")
    print(stderr.strip())
    ok &= check(status == 2 and "sd above 10 %" in stderr and "light4.png" in stderr and
                "light1.png" not in stderr,
                f"a gain of predicted sd above 10 %: exit 2 naming the image (got {status})")
    return ok


def per_light(clayfit, folder):
    """A gain per light: (1) six photos under six lights: the same fit as a
    gain per image; (2) eight photos under four lights, each light in two
    photos at its own power (+-20 %): the photos of one light share its gain,
    which is found (relative to the lights' mean log) within 2 % (8-bit)."""
    lights = [(0.0, 0.0, 1.0), (0.5, 0.0, 0.866), (-0.5, 0.0, 0.866), (0.3, 0.3, 0.906),
              (0.0, 0.5, 0.866), (0.0, -0.5, 0.866)]
    path = ortho_capture(os.path.join(folder, "six"), lights, [1, 0.9, 1.1, 0.85, 1.2, 1.0],
                         "six lights, one per photo")
    a = fit_model(clayfit, path, os.path.join(folder, "six", "per_image"), "M0",
                  "--fit-gains", "per-image")
    b = fit_model(clayfit, path, os.path.join(folder, "six", "per_light"), "M0",
                  "--fit-gains", "per-light")
    ok = check(gains_of(a) == gains_of(b) and a["params"] == b["params"],
               "one light per photo: per-light gains are per-image gains (the same fit)")
    power = {0: 0.85, 1: 1.15, 2: 1.0, 3: 1.2}
    use = [0, 1, 2, 3, 0, 1, 2, 3]
    distinct = [lights[0], lights[1], lights[2], lights[4]]
    path = ortho_capture(os.path.join(folder, "eight"), [distinct[u] for u in use],
                         [power[u] for u in use], "four lights, two photos each")
    c = fit_model(clayfit, path, os.path.join(folder, "eight", "per_light"), "M0",
                  "--fit-gains", "per-light")
    gains = [e for e, _ in gains_of(c)]
    ok &= check(all(gains[k] == gains[k + 4] for k in range(4)),
                "the two photos of each light share its gain")
    mean_log = sum(math.log(power[u]) for u in range(4)) / 4
    worst = max(abs(gains[u] / (power[u] / math.exp(mean_log)) - 1) for u in range(4))
    ok &= check(worst < 0.02, f"the lights' powers found within 2 %: worst {100 * worst:.2f} %")
    return ok


def lights_capture(folder, lights, truth, declared, images, name):
    """An orthographic capture of a Lambertian sphere (8-bit, linear): each of
    its `images` photos lit by every light of `lights` (the capture's
    `directional` lights) at the irradiance truth[j], declared declared[j]
    (an irradiance of 4 in a photo is 200 of 255 where the light faces the
    point: two lights of 2 each stay below the clip level). Its noise model
    is the 8-bit rounding's, sd 1/255/sqrt(12): without one, sigma comes from
    the best start's residuals, taken with every gain at 1, and was 19 times
    too large as declared below (+15 %, -10 %)."""
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    # an albedo of 0.62 (ortho_capture)
    rows, mask = sphere_photo(lambda n: [sum(e / 4 * facing(n, l) for l, e in zip(lights, truth))])
    names = [f"photo{k + 1}.png" for k in range(images)]
    for n in names:
        write_png(os.path.join(folder, n), rows)
    write_png(os.path.join(folder, "mask.png"), mask)
    path = write_ortho_capture(folder, name, names, [
        {"type": "directional", "direction": list(l), "irradiance": [e, e, e]}
        for l, e in zip(lights, declared)])
    with open(path) as f:
        capture = json.load(f)
    capture["noise"] = {"read": 1 / 255 / math.sqrt(12), "shot": 0.0}
    with open(path, "w") as f:
        json.dump(capture, f, indent=1)
    return path


def refused_lights(clayfit, path, out, expect, what):
    """--fit-gains per-light on path: exit 2 before any fit, the message
    holding every string of expect, no fit.json."""
    status, stderr = run(clayfit, "fit", path, "-o", out, "--model", "M0", "--fit-gains",
                         "per-light")
    print(stderr.strip())
    ok = check(status == 2 and all(e in stderr for e in expect),
               f"{what}: exit 2 (got {status}), the message says {expect}")
    return ok & check(not os.path.exists(os.path.join(out, "fit.json")), "no fit.json")


def several_lights(clayfit, folder):
    """A gain per light inside each photo's sum over its lights: three photos,
    each lit by two directional lights of irradiance 2, declared 2.3 and 1.8
    (+15 %, -10 %). Fitted as declared, M0's albedo is 2.6 % low (40 sd),
    and a gain per photo cannot mend it; with --fit-gains per-light the
    lights' gains are found within 2 sd of the truth (true / declared, their
    mean log 0: the gauge), and the material equals the fit of the true
    intensities at the declared lights' mean level (the gauge leaves the
    overall level to them) within 2 sd. Refused (exit 2, no fit.json): two
    lights from one direction in every photo (only their sum is seen; the
    message names both), and one light lighting every photo (its gain is
    the scale)."""
    lights = [(0.5, 0.0, 0.866), (-0.4, 0.3, 0.866)]
    truth, declared = [2.0, 2.0], [2.3, 1.8]
    path = lights_capture(os.path.join(folder, "two"), lights, truth, declared, 3,
                          "two lights in every photo, declared +15 % and -10 % off")
    plain = fit_model(clayfit, path, os.path.join(folder, "two", "plain"), "M0")
    fitted = fit_model(clayfit, path, os.path.join(folder, "two", "fit"), "M0", "--fit-gains",
                       "per-light")
    level = math.sqrt(declared[0] * declared[1] / (truth[0] * truth[1]))  # the gauge
    known = fit_model(clayfit, lights_capture(os.path.join(folder, "known"), lights, truth,
                                              [t * level for t in truth], 3,
                                              "two lights, their true ratio at the declared level"),
                      os.path.join(folder, "known", "fit"), "M0")
    gains = fitted.get("light_gains", [])
    ok = check(len(gains) == 2 and [g["light"] for g in gains] == ["light 1", "light 2"],
               "fit.json light_gains: one per light of the capture file, named")
    mean_log = sum(math.log(t / d) for t, d in zip(truth, declared)) / 2
    for g, t, d in zip(gains, truth, declared):
        want = t / d / math.exp(mean_log)
        ok &= check(g["sd"] > 0 and abs(g["gain"] - want) < 2 * g["sd"],
                    f"{g['light']}: gain {g['gain']:.5f} +- {g['sd']:.2g} against {want:.5f}, "
                    f"{abs(g['gain'] - want) / g['sd']:.2f} sd")
    same = {name: value for name, value, _ in material(known)}
    for name, value, sd in material(fitted):
        ok &= check(name in same and abs(value - same[name]) < 2 * sd,
                    f"{name}: {value:.6g} +- {sd:.2g} against {same.get(name, 0):.6g} with the "
                    f"true intensities, {abs(value - same.get(name, 0)) / sd:.2f} sd")
    a, b = plain["params"]["albedo"], known["params"]["albedo"]
    ok &= check(abs(a["value"][0] - b["value"][0]) > 10 * a["sd"][0],
                f"without the gains the albedo is off: {a['value'][0]:.6g} +- {a['sd'][0]:.2g} "
                f"against {b['value'][0]:.6g}")
    ok &= refused_lights(
        clayfit, lights_capture(os.path.join(folder, "along"), [lights[0], lights[0]], truth,
                                declared, 3, "two lights from one direction in every photo"),
        os.path.join(folder, "along", "fit"),
        ["told from the material", "light 1; light 2", "photo1.png"],
        "two lights from one direction")
    ok &= refused_lights(
        clayfit, lights_capture(os.path.join(folder, "one"), lights[:1], [4.0], [4.0], 3,
                                "one light in every photo"),
        os.path.join(folder, "one", "fit"), ["one light lights every image"],
        "one light for every photo")
    return ok


def white_balance(clayfit, folder):
    """Eight photos under eight lights of different colours (an RGB gain per
    photo, +-15 % overall and +-10 % per channel): --fit-gains per-image-rgb
    finds every red and blue gain against green (each channel's mean log 0)
    within 1 %, and fits the photos (8-bit) far better than a gain per image."""
    lights = [(0.0, 0.0, 1.0), (0.5, 0.0, 0.866), (-0.5, 0.0, 0.866), (0.3, 0.3, 0.906),
              (0.0, 0.5, 0.866), (0.0, -0.5, 0.866), (-0.3, -0.3, 0.906), (0.3, -0.3, 0.906)]
    draw = random.Random(23)
    gains = []
    for _ in lights:
        level = draw.uniform(0.85, 1.15)
        gains.append([level * draw.uniform(0.9, 1.1) for _ in range(3)])
    path = ortho_capture(folder, lights, gains, "eight lights of different colours")
    rgb = fit_model(clayfit, path, os.path.join(folder, "rgb"), "M0", "--fit-gains",
                    "per-image-rgb")
    grey = fit_model(clayfit, path, os.path.join(folder, "grey"), "M0", "--fit-exposures")
    worst = 0.0
    for c in (0, 2):  # red and blue against green, each's mean log over the images 0
        ratio = [g[c] / g[1] for g in gains]
        mean_log = sum(math.log(x) for x in ratio) / len(ratio)
        for image, x in zip(rgb["residuals"]["per_image"], ratio):
            worst = max(worst, abs(image["white_balance"][c] / (x / math.exp(mean_log)) - 1))
    ok = check(worst < 0.01, f"the red and blue gains found within 1 %: worst {100 * worst:.2f} %")
    errors = [d["residuals"]["relative_rmse"] for d in (rgb, grey)]
    ok &= check(errors[0] < 0.5 * errors[1], f"relative RMSE {100 * errors[0]:.2f} % with the "
                f"white balance, {100 * errors[1]:.2f} % with a gain per image")
    return ok


def diligent(clayfit, folder, capture, shared):
    """The real DiLiGenT ball, M4, default budget, with and without gains."""
    if not os.path.exists(os.path.join(shared, "diligent_ball", "001.png")):
        print(f"skipped: {shared}/diligent_ball is absent")
        sys.exit(77)
    plain = fit_model(clayfit, capture, os.path.join(folder, "plain"), "M4")
    gains = fit_model(clayfit, capture, os.path.join(folder, "gains"), "M4", "--fit-exposures")
    ok = check(len(gains_of(gains)) == 96, "96 gains")
    ok &= check(all(0.8 < e < 1.2 and 0 < sd < 0.1 * e for e, sd in gains_of(gains)),
                "every gain within 20 % of 1, its sd above 0 and below 10 %")
    rest = [d["residuals"]["highlight_cores"]["rest"]["relative_rmse"] for d in (plain, gains)]
    ok &= check(rest[1] < rest[0], f"the core-free relative RMSE lower with the gains: "
                f"{100 * rest[1]:.2f} % against {100 * rest[0]:.2f} %")
    return ok


def fit_model(clayfit, capture, out, model, *options):
    status, stderr = run(clayfit, "fit", capture, "-o", out, "--model", model, *options)
    if status != 0:
        sys.exit(f"clayfit fit {capture} {' '.join(options)}: exit {status}: {stderr.strip()}")
    with open(os.path.join(out, "fit.json")) as f:
        return json.load(f)


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    mode, clayfit, folder = sys.argv[1], sys.argv[2], sys.argv[3]
    if mode == "diligent" and len(sys.argv) == 6:
        sys.exit(0 if diligent(clayfit, folder, sys.argv[4], sys.argv[5]) else 1)
    modes = {"capture": make_capture, "default": default_budget, "recover": recover,
             "refused": refused, "per-light": per_light, "several-lights": several_lights,
             "white-balance": white_balance}
    if mode not in modes:
        sys.exit(__doc__)
    sys.exit(0 if modes[mode](clayfit, folder) else 1)


if __name__ == "__main__":
    main()
