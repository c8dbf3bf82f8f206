#!/usr/bin/env python3
"""Fixtures for the hostile-input tests of captures (tests/capture/hostile.cmake):
in DIR, one small capture per case, each broken in one way.

usage: make_hostile_captures.py CLAYFIT DIR

From `clayfit synth` (COLMAP camera, 16-bit PNGs 96 x 72, masks):
  bomb_png         images/001.png's header patched to claim 26000 x 26000
  truncated_png    images/001.png cut in the middle of its pixel data
  duplicate_image  images.files lists 000.png twice
  black_mask       masks/001.png all 0 (no usable pixel)
  mixed_depth      images/001.png from the same scene in 8 bits
  huge_radius      geometry.radius 1e308 (the limit is 1e300)
  bom_colmap       images.files[0] starts with a UTF-8 byte-order mark
  fine             unchanged (the cap on decoded bytes)
Written here (orthographic camera, a normal map, DiLiGenT's text files):
  text_ok          as DiLiGenT gives them: filenames.txt, light_directions.txt,
                   light_intensities.txt
  text_subnormal   an intensity of 1e-320 (subnormal, finite)
  text_comment     a '#' comment line in filenames.txt
  text_rows        light_directions.txt one row short
  text_bom         filenames.txt and light_directions.txt begin with a BOM
  text_nul         a NUL byte in light_directions.txt, line 2
  bom_path         images.files instead of the list, the first name after a
                   UTF-8 byte-order mark
  env_nan          an environment light whose map (PFM) has a NaN at texel
                   (5, 21), channel 2
  env_bomb         the environment map a PNG whose header claims 26000 x 26000
  normal_bomb      the normal map a PNG whose header claims 26000 x 26000
  env_ok           the environment map fine (64 x 32, the cap's test)
From `clayfit synth --format jpg --exif-exposures` (issue 30, items 5 and 8),
images/001.jpg changed:
  jpeg_ok          unchanged
  jpeg_cut_scan    cut 10 bytes into its scan (after the SOS header)
  jpeg_half        cut in half
  jpeg_no_eoi      without its end-of-image marker (the last 2 bytes)
  jpeg_noise       1 % of its entropy-coded bytes replaced by random bytes
                   (seed 3; libjpeg warns of corrupt data)
  jpeg_noise_run   16 random bytes in the middle of its scan (seed 7)
  exif_time_huge   EXIF exposure time 4294967295/1 s
  exif_time_tiny   EXIF exposure time 1/4294967295 s
  exif_f_huge      EXIF f-number 4294967295/1
  exif_iso_huge    EXIF ISO a LONG 4294967295
  exif_spread      EXIF exposure time 1000 s, each field in range, but
                   10^5 times the others' (1/100 s at ISO 100, f/4)
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


def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data +
            struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def write_png(path, width, height, colour_type, depth, sample):
    """A PNG of one value everywhere (colour type 0 grey or 2 RGB)."""
    channels = {0: 1, 2: 3}[colour_type]
    bytes_per = depth // 8
    pixel = sample.to_bytes(bytes_per, "big") * channels
    raw = b"".join(b"\0" + pixel * width for _ in range(height))
    ihdr = struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) +
                chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def patch_png_size(path, width, height):
    """Rewrite IHDR's width and height (and its CRC): the pixel data stays
    that of the small image."""
    data = bytearray(open(path, "rb").read())
    assert data[12:16] == b"IHDR"
    data[16:24] = struct.pack(">II", width, height)
    data[29:33] = struct.pack(">I", zlib.crc32(bytes(data[12:29])) & 0xFFFFFFFF)
    open(path, "wb").write(data)


def edit_json(path, change):
    doc = json.load(open(path))
    change(doc)
    json.dump(doc, open(path, "w"), indent=2, ensure_ascii=False)


def synth(clayfit, out, fmt):
    subprocess.run([clayfit, "--quiet", "synth", "-o", out, "--images", "3", "--size",
                    "96x72", "--format", fmt, "--masks", "--supersample", "1", "--seed", "4"],
                   check=True)


def colmap_cases(clayfit, root):
    base = os.path.join(root, "base_png16")
    synth(clayfit, base, "png16")
    eight = os.path.join(root, "base_png8")
    synth(clayfit, eight, "png8")

    def case(name):
        path = os.path.join(root, name)
        shutil.copytree(base, path)
        return path

    case("fine")
    patch_png_size(os.path.join(case("bomb_png"), "images", "001.png"), 26000, 26000)
    cut = os.path.join(case("truncated_png"), "images", "001.png")
    data = open(cut, "rb").read()
    open(cut, "wb").write(data[: len(data) // 2])
    edit_json(os.path.join(case("duplicate_image"), "capture.json"),
              lambda d: d["images"].__setitem__("files", ["000.png", "001.png", "000.png"]))
    write_png(os.path.join(case("black_mask"), "masks", "001.png"), 96, 72, 0, 8, 0)
    shutil.copy(os.path.join(eight, "images", "001.png"),
                os.path.join(case("mixed_depth"), "images", "001.png"))
    edit_json(os.path.join(case("huge_radius"), "capture.json"),
              lambda d: d["geometry"].__setitem__("radius", 1e308))
    edit_json(os.path.join(case("bom_colmap"), "capture.json"),
              lambda d: d["images"]["files"].__setitem__(0, "\ufeff000.png"))


def write_pfm_normals(path, size):
    """A sphere's normals, facing +z, in a size x size map (PFM, rows bottom
    to top); outside the disc 0 (no surface)."""
    r = size * 0.4
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            u, v = (x + 0.5 - size / 2) / r, -(y + 0.5 - size / 2) / r
            w2 = 1.0 - u * u - v * v
            row += [u, v, w2 ** 0.5] if w2 > 0 else [0.0, 0.0, 0.0]
        rows.append(row)
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (size, size))
        for row in reversed(rows):
            f.write(struct.pack("<%df" % len(row), *row))


def text_cases(root):
    size, names = 32, ["000.png", "001.png", "002.png"]
    ok = os.path.join(root, "text_ok")
    os.makedirs(ok)
    for name in names:
        write_png(os.path.join(ok, name), size, size, 0, 16, 20000)
    write_pfm_normals(os.path.join(ok, "normals.pfm"), size)
    capture = {
        "clayfit_capture": 1,
        "name": "text files",
        "camera": {"type": "orthographic", "view": [0, 0, 1]},
        "images": {"list": "filenames.txt"},
        "colour": {"encoding": "linear"},
        "radiometry": "relative",
        "geometry": {"type": "normal_map", "file": "normals.pfm", "margin_px": 1},
        "lights": [{"type": "directional_per_image", "directions": "light_directions.txt",
                    "intensities": "light_intensities.txt"}],
    }
    json.dump(capture, open(os.path.join(ok, "capture.json"), "w"), indent=2)
    texts = {
        "filenames.txt": "".join(n + "\n" for n in names),
        "light_directions.txt": "0.1 0.2 0.97\n-0.2 0.1 0.97\n0 0 1\n",
        "light_intensities.txt": "1 1 1\n1 1 1\n1 1 1\n",
    }

    def case(name, **changes):
        path = os.path.join(root, name)
        shutil.copytree(ok, path)
        for file, text in {**texts, **{k.replace("_txt", ".txt"): v
                                       for k, v in changes.items()}}.items():
            data = text if isinstance(text, bytes) else text.encode()
            open(os.path.join(path, file), "wb").write(data)

    for file, text in texts.items():
        open(os.path.join(ok, file), "w").write(text)
    case("text_subnormal", light_intensities_txt="1 1 1\n1e-320 1 1\n1 1 1\n")
    case("text_comment", filenames_txt="# the ball, 3 lights\n" + texts["filenames.txt"])
    case("text_rows", light_directions_txt="0.1 0.2 0.97\n# a comment\n0 0 1\n")
    case("text_bom", filenames_txt="\ufeff" + texts["filenames.txt"],
         light_directions_txt="\ufeff" + texts["light_directions.txt"])
    case("text_nul", light_directions_txt=b"0.1 0.2 0.97\n-0.2 0.1\x00 0.97\n0 0 1\n")
    case("bom_path")
    edit_json(os.path.join(root, "bom_path", "capture.json"),
              lambda d: d.__setitem__("images", {"files": ["\ufeff" + names[0]] + names[1:]}))


def write_pfm(path, width, height, texel):
    """An RGB PFM map, texel(x, y) its value at column x and row y from the
    top (PFM stores the rows bottom to top)."""
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (width, height))
        for y in reversed(range(height)):
            f.write(b"".join(struct.pack("<3f", *texel(x, y)) for x in range(width)))


def map_cases(root):
    """From text_ok: an environment light instead of the directional ones,
    and the maps broken."""
    ok = os.path.join(root, "text_ok")

    def case(name, light_file):
        path = os.path.join(root, name)
        shutil.copytree(ok, path)
        edit_json(os.path.join(path, "capture.json"), lambda d: d.__setitem__(
            "lights", [{"type": "environment", "file": light_file, "count": 8}]))
        return path

    sky = lambda x, y: (50.0, 50.0, 50.0) if y < 8 and 20 <= x < 26 else (0.2, 0.2, 0.2)
    write_pfm(os.path.join(case("env_ok", "sky.pfm"), "sky.pfm"), 64, 32, sky)
    write_pfm(os.path.join(case("env_nan", "sky.pfm"), "sky.pfm"), 64, 32,
              lambda x, y: (0.2, 0.2, math.nan) if (x, y) == (5, 21) else sky(x, y))
    bomb = os.path.join(case("env_bomb", "sky.png"), "sky.png")
    write_png(bomb, 64, 32, 2, 8, 40)
    patch_png_size(bomb, 26000, 26000)
    normals = os.path.join(case("normal_bomb", "sky.pfm"), "normals.png")
    write_pfm(os.path.join(root, "normal_bomb", "sky.pfm"), 64, 32, sky)
    write_png(normals, 32, 32, 2, 8, 255)
    patch_png_size(normals, 26000, 26000)
    edit_json(os.path.join(root, "normal_bomb", "capture.json"),
              lambda d: d["geometry"].__setitem__("file", "normals.png"))


def jpeg_scan_start(data):
    """The first byte of the entropy-coded data: after the SOS segment."""
    at = 2
    while True:
        assert data[at] == 0xFF, "a JPEG marker at byte %d" % at
        marker, length = data[at + 1], data[at + 2] << 8 | data[at + 3]
        if marker == 0xDA:
            return at + 2 + length
        at += 2 + length


def patch_exif(data, tag, kind, value):
    """The JPEG's EXIF entry `tag` (in the Exif SubIFD clayfit's writer
    makes: little-endian TIFF) given the type kind (3 SHORT, 4 LONG, 5
    RATIONAL) and value: an int, or (numerator, denominator) written where
    the entry's rational was."""
    data = bytearray(data)
    at = data.index(b"Exif\0\0") + 6
    u16 = lambda o: struct.unpack_from("<H", data, at + o)[0]
    u32 = lambda o: struct.unpack_from("<I", data, at + o)[0]

    def entries(ifd):
        return [ifd + 2 + 12 * i for i in range(u16(ifd))]

    sub = next(u32(e + 8) for e in entries(u32(4)) if u16(e) == 0x8769)
    entry = next(e for e in entries(sub) if u16(e) == tag)
    if kind == 5:
        struct.pack_into("<HII", data, at + entry + 2, 5, 1, u32(entry + 8))
        struct.pack_into("<II", data, at + u32(entry + 8), *value)
    else:
        struct.pack_into("<HII", data, at + entry + 2, kind, 1, value)
    return bytes(data)


def jpeg_cases(clayfit, root):
    base = os.path.join(root, "base_jpg")
    subprocess.run([clayfit, "--quiet", "synth", "-o", base, "--images", "3", "--size",
                    "96x72", "--format", "jpg", "--exif-exposures", "--masks",
                    "--supersample", "1", "--seed", "4"], check=True)
    photo = open(os.path.join(base, "images", "001.jpg"), "rb").read()
    scan = jpeg_scan_start(photo)

    def case(name, data):
        path = os.path.join(root, name)
        shutil.copytree(base, path)
        open(os.path.join(path, "images", "001.jpg"), "wb").write(data)

    def noise(seed, runs, length):
        rng, data = random.Random(seed), bytearray(photo)
        for _ in range(runs):
            at = rng.randrange(scan, len(photo) - 2 - length)
            data[at:at + length] = bytes(rng.randrange(256) for _ in range(length))
        return bytes(data)

    case("jpeg_ok", photo)
    case("jpeg_cut_scan", photo[:scan + 10])
    case("jpeg_half", photo[:len(photo) // 2])
    case("jpeg_no_eoi", photo[:-2])
    case("jpeg_noise", noise(3, (len(photo) - scan) // 100, 1))
    case("jpeg_noise_run", noise(7, 1, 16))
    case("exif_time_huge", patch_exif(photo, 0x829A, 5, (4294967295, 1)))
    case("exif_time_tiny", patch_exif(photo, 0x829A, 5, (1, 4294967295)))
    case("exif_f_huge", patch_exif(photo, 0x829D, 5, (4294967295, 1)))
    case("exif_iso_huge", patch_exif(photo, 0x8827, 4, 4294967295))
    case("exif_spread", patch_exif(photo, 0x829A, 5, (1000, 1)))


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    clayfit, root = sys.argv[1], sys.argv[2]
    shutil.rmtree(root, ignore_errors=True)
    os.makedirs(root)
    colmap_cases(clayfit, root)
    text_cases(root)
    map_cases(root)
    jpeg_cases(clayfit, root)
    return 0


if __name__ == "__main__":
    sys.exit(main())
