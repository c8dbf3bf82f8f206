#!/usr/bin/env python3
"""Hostile names through every export format (issue 16, items 1 and 3).

The capture's name, its path (both from fit.json) and the fit file's own
path (the command line) are untrusted text. For each hostile variant, a
copy of the template fit.json gets the name and path, is put in a folder
whose name is hostile too, and is exported to every format. Asserted:

  blender   the script compiles (ast.parse), its AST is the clean export's
            (no statement was injected), running it with a stub `bpy` runs
            no injected code, and the provenance comment, un-escaped (\\\\,
            \\n, \\r, \\t, \\xNN), gives back the name and both paths;
  mtlx, mtlx-openpbr, mitsuba
            the file parses (xml.etree), has one comment, the same elements
            and attributes as the clean export, and the un-escaped comment
            gives back the name and both paths;
  json, gltf
            the file parses and its provenance holds the name and paths as
            they are (a byte of invalid UTF-8 in a path as U+FFFD).

A name holding \\u0000 is refused (exit 2) with the file and place named,
in clayfit's words (not Jansson's JSON_ALLOW_NUL).

usage: check_export_hostile.py CLAYFIT TEMPLATE_FIT.json OUTDIR
"""
import ast
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

FORMATS = ["json", "mtlx", "mtlx-openpbr", "gltf", "blender", "mitsuba"]
SUFFIX = {"json": "json", "mtlx": "mtlx", "mtlx-openpbr": "mtlx", "gltf": "gltf",
          "blender": "py", "mitsuba": "xml"}

# What a hostile name tries: code after a newline (Python comment), ending
# an XML comment, markup, quotes and triple quotes, backslashes, control
# characters, Unicode line breaks, a trailing '-'.
INJECT = '__import__("pathlib").Path("INJECTED_{}").touch()'
NAMES = [
    "evil\n" + INJECT.format("NAME_LF") + "\r" + INJECT.format("NAME_CR") +
    "\r\n# ' \" \"\"\" ''' \\ back\\slash \\n \\x41 end\\",
    "-xml --> <evil a='1'/> <!-- -- --- </script><script>alert(1)</script> & &amp; &#60; "
    "ctl \t\x01\x07\x0b\x0c\x1b[31m\x7f \u0085 \u2028 \u2029 \u202e \ufeff end-",
    "",
]
CAPTURE_PATH = "cap\n" + INJECT.format("CAPTURE") + "\n--> <x> \"q\" 'q' &amp; \\.json"
FOLDER = b"dir\n" + INJECT.format("FOLDER").encode() + b"\n--> <!-- & \"'\\"
FOLDER_BAD_UTF8 = b"bad\xff\xfe\xc3(utf8\xe2\x82"


def unescape_comment(data):
    """The comment escapes of src/core/text_escape.c, back to bytes."""
    table = {b"\\\\": b"\\", b"\\n": b"\n", b"\\r": b"\r", b"\\t": b"\t"}

    def one(m):
        s = m.group(0)
        return table[s] if s in table else bytes([int(s[2:], 16)])
    return re.sub(rb"\\(\\|n|r|t|x[0-9a-fA-F]{2})", one, data)


def run_export(clayfit, fit, fmt, out):
    r = subprocess.run([clayfit, "--quiet", "export", fit, "--format", fmt, "-o", out],
                       capture_output=True)
    if r.returncode != 0:
        return f"exit {r.returncode}: {r.stderr.decode(errors='replace')}"
    return None


def run_with_stub_bpy(script, workdir):
    """Run the script's top level (not build()) with an empty bpy module."""
    runner = ("import sys, types\nsys.modules['bpy'] = types.ModuleType('bpy')\n"
              "src = open(sys.argv[1], 'rb').read()\n"
              "exec(compile(src, sys.argv[1], 'exec'), {'__name__': 'preset'})\n")
    r = subprocess.run([sys.executable, "-c", runner, os.path.abspath(script)], cwd=workdir,
                       capture_output=True)
    if r.returncode != 0:
        return f"the script failed to run: {r.stderr.decode(errors='replace')}"
    planted = [f for f in os.listdir(workdir) if f.startswith("INJECTED")]
    return f"injected code ran: created {planted}" if planted else None


def comments(data):
    return re.findall(rb"<!--(.*?)-->", data, re.S)


def xml_shape(data):
    root = ET.fromstring(data)
    return [(e.tag, sorted(e.attrib.items())) for e in root.iter()]


def provenance_line(text, marker):
    for line in text.split(b"\n"):
        if marker in line:
            return line
    return None


def check_comment_provenance(data, expect):
    """The provenance line, un-escaped, holds every expected piece."""
    line = provenance_line(data, b"; capture: ")
    if line is None:
        return "no provenance line"
    raw = unescape_comment(line)
    for label, value in expect:
        if value not in raw:
            return f"{label} {value!r} not in the un-escaped provenance {raw!r}"
    return None


def check_blender(data, clean, expect, out_dir):
    try:
        tree = ast.parse(data.decode("utf-8"))
    except (SyntaxError, ValueError, UnicodeDecodeError) as e:
        return f"does not compile: {e}"
    if ast.dump(tree) != ast.dump(ast.parse(clean.decode("utf-8"))):
        return "the AST differs from the clean export's: something was injected"
    header = data.split(b"\nimport bpy")[0]
    for i, line in enumerate(header.split(b"\n")):
        if line and not line.startswith(b"#"):
            return f"header line {i + 1} is not a comment: {line!r}"
    problem = check_comment_provenance(data, expect)
    if problem:
        return problem
    return None


def check_xml(data, clean, expect):
    try:
        shape = xml_shape(data)
    except ET.ParseError as e:
        return f"not well-formed XML: {e}"
    if shape != xml_shape(clean):
        return "elements or attributes differ from the clean export's"
    found = comments(data)
    if len(found) != 1:
        return f"{len(found)} comments instead of 1"
    if b"--" in found[0] or found[0].endswith(b"-"):
        return "the comment holds '--' or ends with '-'"
    return check_comment_provenance(found[0], expect)


def strings_in(node):
    if isinstance(node, str):
        yield node
    elif isinstance(node, dict):
        for v in node.values():
            yield from strings_in(v)
    elif isinstance(node, list):
        for v in node:
            yield from strings_in(v)


def check_json(data, expect_text):
    try:
        doc = json.loads(data.decode("utf-8"))
    except (ValueError, UnicodeDecodeError) as e:
        return f"not JSON: {e}"
    everything = "\n".join(strings_in(doc))
    for label, value in expect_text:
        if value not in everything:
            return f"{label} {value!r} not in the document's strings"
    return None


def check_one(clayfit, fmt, fit, out, clean, expect, expect_text, work):
    problem = run_export(clayfit, fit, fmt, out)
    if problem:
        return problem
    with open(out, "rb") as f:
        data = f.read()
    if fmt == "blender":
        problem = check_blender(data, clean, expect, work)
        return problem or run_with_stub_bpy(out, work)
    if fmt in ("mtlx", "mtlx-openpbr", "mitsuba"):
        return check_xml(data, clean, expect)
    return check_json(data, expect_text)


def check_nul(clayfit, template, outdir):
    fit = os.path.join(outdir, "nul", "fit.json")
    os.makedirs(os.path.dirname(fit), exist_ok=True)
    doc = dict(template)
    doc["capture"] = dict(template["capture"], name="before\u0000after")
    with open(fit, "w") as f:
        json.dump(doc, f)
    r = subprocess.run([clayfit, "--quiet", "export", fit, "--format", "blender", "-o",
                        os.path.join(outdir, "nul", "never.py")], capture_output=True, text=True)
    if r.returncode != 2:
        return [f"NUL name: exit {r.returncode}, expected 2"]
    if fit not in r.stderr or "\\u0000" not in r.stderr or "JSON_ALLOW_NUL" in r.stderr:
        return [f"NUL name: the message does not name the file and the \\u0000: {r.stderr}"]
    return []


def main():
    clayfit, template_path, outdir = sys.argv[1], sys.argv[2], sys.argv[3]
    with open(template_path) as f:
        template = json.load(f)
    shutil.rmtree(outdir, ignore_errors=True)
    work = os.path.join(outdir, "run")
    os.makedirs(work)
    clean_fit = os.path.join(outdir, "clean", "fit.json")
    os.makedirs(os.path.dirname(clean_fit))
    shutil.copy(template_path, clean_fit)
    clean = {}
    for fmt in FORMATS:
        out = os.path.join(outdir, "clean", "preset." + SUFFIX[fmt])
        problem = run_export(clayfit, clean_fit, fmt, out)
        if problem:
            print(f"clean export {fmt}: {problem}")
            return 1
        with open(out, "rb") as f:
            clean[fmt] = f.read()

    failures = []
    cases = [(i, name, FOLDER + b"%d" % i) for i, name in enumerate(NAMES)]
    cases.append((len(NAMES), "plain", FOLDER_BAD_UTF8))
    for i, name, folder in cases:
        folder_path = os.path.join(os.fsencode(outdir), folder)
        os.makedirs(folder_path, exist_ok=True)
        fit = os.path.join(folder_path, b"fit.json")
        doc = dict(template)
        doc["capture"] = dict(template["capture"], name=name, path=CAPTURE_PATH)
        with open(fit, "w") as f:
            json.dump(doc, f)
        # the capture path as export reports it: joined to fit.json's folder
        capture_bytes = os.path.join(folder_path, CAPTURE_PATH.encode())
        expect = [("name", b"capture: " + name.encode() + b" ("), ("fit path", fit),
                  ("capture path", capture_bytes)]
        def decoded(b):  # each byte of invalid UTF-8 as U+FFFD, as text_escape_utf8
            return re.sub("[\udc80-\udcff]", "\ufffd", b.decode("utf-8", "surrogateescape"))
        expect_text = [("name", name), ("fit path", decoded(fit)),
                       ("capture path", decoded(capture_bytes))]
        for fmt in FORMATS:
            out = os.path.join(folder_path, b"preset." + SUFFIX[fmt].encode())
            problem = check_one(clayfit, fmt, fit, out, clean[fmt], expect, expect_text, work)
            if problem:
                failures.append(f"variant {i} {name!r}, {fmt}: {problem}")
    failures += check_nul(clayfit, template, outdir)
    for f in failures:
        print(f)
    print(f"{len(cases)} variants x {len(FORMATS)} formats + NUL: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
