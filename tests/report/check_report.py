#!/usr/bin/env python3
"""Checks a `clayfit report` folder: report.json valid against its schema,
every picture and plot it lists present (PNG pictures of one size per image,
SVG plots well-formed XML), the page naming every one of them, and the
number of images expected.

usage: check_report.py DIR SCHEMA IMAGES"""
import json
import os
import struct
import sys
import xml.etree.ElementTree as ET

import jsonschema


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    return struct.unpack(">II", head[16:24])


def main():
    folder, schema_path, images = sys.argv[1], sys.argv[2], int(sys.argv[3])
    with open(os.path.join(folder, "report.json")) as f:
        doc = json.load(f)
    with open(schema_path) as f:
        jsonschema.Draft202012Validator(json.load(f)).validate(doc)
    with open(os.path.join(folder, doc["page"])) as f:
        page = f.read()
    failures = []
    if len(doc["images"]) != images:
        failures.append(f"{len(doc['images'])} images in report.json, expected {images}")
    for image in doc["images"]:
        sizes = set()
        for kind in ("photo", "render", "residual"):
            path = os.path.join(folder, image[kind])
            if not os.path.isfile(path) or os.path.getsize(path) == 0:
                failures.append(f"{image['name']}: {kind} {image[kind]} missing")
                continue
            sizes.add(png_size(path))
            if f'src="{image[kind]}"' not in page:
                failures.append(f"{image['name']}: {kind} not on the page")
        if len(sizes) > 1:
            failures.append(f"{image['name']}: pictures of different sizes {sizes}")
    for key, name in doc["plots"].items():
        path = os.path.join(folder, name)
        try:
            root = ET.parse(path).getroot()
            if not root.tag.endswith("svg") or len(list(root)) < 3:
                failures.append(f"plot {key}: {name} is not an SVG with content")
        except (OSError, ET.ParseError) as e:
            failures.append(f"plot {key}: {name}: {e}")
        if f'src="{name}"' not in page:
            failures.append(f"plot {key} not on the page")
    for needle in ("Parameters", "Model choice", "Not constrained by this capture", "Speed"):
        if needle not in page:
            failures.append(f"the page has no '{needle}'")
    for failure in failures:
        print("FAIL:", failure)
    print(f"{len(doc['images'])} images, {len(doc['plots'])} plots, residual RMS "
          f"{doc['residuals']['rms_sigma']:.3f} sigma over {doc['residuals']['count']} observations")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
