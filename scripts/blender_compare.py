"""Compare a Blender render with clayfit's own rendering of the same scene,
pixel by pixel inside the sphere (docs/fidelity.md). Runs in Blender's Python,
whose image loader reads OpenEXR (no other dependency):

usage: blender -b --factory-startup --python-exit-code 1 -P scripts/blender_compare.py -- \
           --clayfit CLAYFIT.exr --mask MASK.exr --render BLENDER.exr [--margin PX]
           [--diff DIFF.png] [--json OUT.json]

The pixels compared are those the mask covers fully, at least --margin pixels
(default 2, clayfit's geometry.margin_px) inside the silhouette. The relative
RMSE is clayfit's (fit_residuals.c): sqrt(sum (b - c)^2 / sum c^2) over the
pixels and channels, with c clayfit's value and b Blender's. Also printed: the
ratio of the sums (a global gain), and the relative RMSE after the best gain
(what is left is the shape). The difference image maps (b - c) to grey 0.5 +/-
0.5 at +/- 25 % of clayfit's mean value over the pixels (each channel
apart), black outside the compared pixels.
"""
import argparse
import array
import json
import sys

import bpy

# Plain Python, no numpy: Blender started from another Python's environment
# (a pyenv on PATH) runs that Python's site-packages, which may have none.


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender_compare.py")
    p.add_argument("--clayfit", required=True)
    p.add_argument("--mask", required=True)
    p.add_argument("--render", required=True)
    p.add_argument("--margin", type=int, default=2)
    p.add_argument("--diff")
    p.add_argument("--json")
    return p.parse_args(argv)


def load(path):
    """An image's RGBA floats (w, h, values), bottom row first (Blender's order, the same
    for every file)."""
    image = bpy.data.images.load(path, check_existing=False)
    image.colorspace_settings.name = "Non-Color"  # the stored values, untouched
    w, h = image.size
    if w == 0 or h == 0:
        raise SystemExit(f"blender_compare: cannot read {path}")
    pixels = array.array("f", bytes(4 * 4 * w * h))
    image.pixels.foreach_get(pixels)
    return w, h, pixels


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


def write_diff(path, w, h, c, b, inside, mean):
    scale = 0.25 * mean
    out = array.array("f", [0.0, 0.0, 0.0, 1.0] * (w * h))
    for i in inside:
        for k in range(3):
            d = 0.5 + 0.5 * (b[4 * i + k] - c[4 * i + k]) / scale
            out[4 * i + k] = min(1.0, max(0.0, d))
    image = bpy.data.images.new("diff", w, h, alpha=False, float_buffer=False)
    image.colorspace_settings.name = "Non-Color"
    image.pixels.foreach_set(out)
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()


def main():
    a = parse_args()
    (w, h, c), (wb, hb, b), (wm, hm, m) = load(a.clayfit), load(a.render), load(a.mask)
    if (w, h) != (wb, hb) or (w, h) != (wm, hm):
        raise SystemExit(f"blender_compare: sizes differ: clayfit {w}x{h}, Blender {wb}x{hb}, "
                         f"mask {wm}x{hm}")
    mask = erode([m[4 * i] >= 1.0 - 1e-6 for i in range(w * h)], w, h, a.margin)
    inside = [i for i in range(w * h) if mask[i]]
    if not inside:
        raise SystemExit("blender_compare: the mask leaves no pixel")
    e2 = y2 = bc = bb2 = sum_b = sum_c = peak = max_d = 0.0
    e2k, y2k = [0.0] * 3, [0.0] * 3
    for i in inside:
        for k in range(3):
            cv, bv = float(c[4 * i + k]), float(b[4 * i + k])
            if not (abs(cv) < float("inf") and abs(bv) < float("inf")):
                raise SystemExit(f"blender_compare: pixel {i % w}, {i // w} is not finite")
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
    result = {
        "pixels": len(inside),
        "relative_rmse": (e2 / y2) ** 0.5,
        "sum_ratio": sum_b / sum_c,
        "relative_rmse_after_gain": (after / y2) ** 0.5,
        "relative_rmse_per_channel": [(e2k[k] / y2k[k]) ** 0.5 for k in range(3)],
        "max_abs_diff_over_peak": max_d / peak,
    }
    if a.diff:
        write_diff(a.diff, w, h, c, b, inside, sum_c / (3 * len(inside)))
    text = json.dumps(result)
    print("blender_compare:", text)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            f.write(text + "\n")


main()
