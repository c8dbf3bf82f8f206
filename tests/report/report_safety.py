#!/usr/bin/env python3
"""clayfit report against hostile inputs and interruptions (issue 16).

usage: report_safety.py CASE CLAYFIT FIT_SMALL WORK [SCHEMA]

CASE is one of
  oversized  item 13: a fit.json over the reader's cap (a well-formed 9 MiB
             document, and a 200 MB one) is refused at once, under a 1 GB
             address-space limit, naming the file and the cap (before: the
             report parsed fit.json a second time, without a cap);
  capture    item 10: --capture with a copy of the fit's capture is accepted
             and report.json records the copy and how it was checked; copies
             whose flash is moved, whose flash is brighter, or whose colour
             block has a black level are refused (exit 2) saying what differs,
             and write nothing (before: all accepted, report.json naming the
             fit's capture); when the fit's capture cannot be found, a warning
             and report.json say that only names and counts were compared;
  folders    item 5: -o at a user's folder or a file is refused (exit 2) with
             what to do, and nothing in it is touched; a run killed after a
             random delay, again and again, leaves the earlier report or the
             new one, whole; the next run removes the leftover.
"""
import json
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import time

FAILURES = []


def check(cond, message):
    if not cond:
        FAILURES.append(message)
        print("FAIL:", message)


def run(clayfit, *args, limit_bytes=None, env=None):
    def limit():
        if limit_bytes:
            resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))

    p = subprocess.run([clayfit, "--quiet", *args], capture_output=True, text=True,
                       preexec_fn=limit, timeout=120, env=env)
    return p.returncode, p.stderr


def oversized(clayfit, small, work):
    cap = 8 << 20
    big = os.path.join(work, "big.fit.json")
    with open(big, "w") as f:  # well-formed: {"a": [[], [], ...]}, just over the cap
        f.write('{"a": [' + ",".join(["[]"] * (cap // 3 + 1000)) + "]}")
    sparse = os.path.join(work, "sparse.fit.json")
    with open(sparse, "wb") as f:  # 200 MB without using the disk
        f.truncate(200 << 20)
    for path in (big, sparse):
        size = os.path.getsize(path)
        start = time.monotonic()
        code, err = run(clayfit, "report", path, "-o", os.path.join(work, "never"),
                        limit_bytes=None if os.environ.get("CLAYFIT_SANITIZE") else 1 << 30)
        seconds = time.monotonic() - start
        check(code == 2, f"{path}: exit {code}, expected 2: {err}")
        check(path in err and str(size) in err and str(cap) in err,
              f"{path}: the message does not name the file, its size and the cap {cap}: {err}")
        print(f"{os.path.basename(path)} ({size} bytes): exit {code} in {seconds:.2f} s: {err.strip()}")
    # Under the cap but under a memory limit that Jansson's parse (about 45
    # times the file, 360 MB) does not fit in (250 MB of address space: the
    # process itself takes far less since OpenImageIO is no longer linked): out of memory, a failure while
    # running (exit 1), not "invalid JSON" with an empty reason at -1:-1.
    # Not under AddressSanitizer, whose shadow memory needs no address limit.
    if not os.environ.get("CLAYFIT_SANITIZE"):
        under = os.path.join(work, "under.fit.json")
        with open(under, "w") as f:
            f.write('{"a": [' + ",".join(["[]"] * (cap // 3 - 1000)) + "]}")
        code, err = run(clayfit, "report", under, "-o", os.path.join(work, "never"),
                        limit_bytes=250 << 20)
        check(code == 1 and "out of memory while parsing" in err and under in err,
              f"{under} under 250 MB: exit {code}, expected 1 and 'out of memory': {err}")
        os.remove(under)
    check(not os.path.exists(os.path.join(work, "never")), "a refused fit.json made a report")
    os.remove(big)
    os.remove(sparse)


def copy_capture(small, work, name, edit):
    folder = os.path.join(work, name)
    os.makedirs(folder)
    for part in ("images", "sparse"):
        shutil.copytree(os.path.join(small, part), os.path.join(folder, part))
    with open(os.path.join(small, "capture.json")) as f:
        doc = json.load(f)
    edit(doc)
    path = os.path.join(folder, "capture.json")
    with open(path, "w") as f:
        json.dump(doc, f, indent=2)
    return path


def capture(clayfit, small, work, schema):
    fit = os.path.join(small, "auto", "fit.json")

    def move_flash(doc):
        doc["lights"][0]["offset"][0] += 0.05

    def brighter(doc):
        doc["lights"][0]["intensity"] = [x * 1.05 for x in doc["lights"][0]["intensity"]]

    def black_level(doc):
        doc["colour"]["black_level"] = 0.001

    same = copy_capture(small, work, "same", lambda doc: None)
    out = os.path.join(work, "same_report")
    code, err = run(clayfit, "report", fit, "-o", out, "--capture", same)
    check(code == 0, f"a copy of the fit's capture: exit {code}: {err}")
    if code == 0:
        with open(os.path.join(out, "report.json")) as f:
            doc = json.load(f)
        if schema:
            import jsonschema
            with open(schema) as f:
                jsonschema.Draft202012Validator(json.load(f)).validate(doc)
        check(doc["capture"]["path"] == same,
              f"report.json names {doc['capture']['path']}, not the capture used, {same}")
        check(doc["capture"].get("fit_capture", "").endswith("capture.json"),
              f"report.json lacks the fit's capture: {doc['capture']}")
        check("lights, colours and observations compared" in doc["capture"].get("check", ""),
              f"report.json does not say how the capture was checked: {doc['capture']}")
    # the fit's capture not found (fit.json moved away from it): names and
    # counts only, said on stderr and in report.json
    lonely = os.path.join(work, "lonely")
    os.makedirs(lonely)
    shutil.copy(fit, lonely)
    out = os.path.join(work, "lonely_report")
    code, err = run(clayfit, "report", os.path.join(lonely, "fit.json"), "-o", out,
                    "--capture", same)
    check(code == 0 and "warning" in err and "names and counts only" in err,
          f"the fit's capture missing: exit {code}: {err}")
    if code == 0:
        with open(os.path.join(out, "report.json")) as f:
            doc = json.load(f)
        check(doc["capture"]["path"] == same and
              doc["capture"].get("check", "").startswith("images' names and counts only"),
              f"the fit's capture missing: report.json says {doc['capture']}")
    cases = [("moved_flash", move_flash, "the lights differ (a direction or position)"),
             ("brighter_flash", brighter, "the lights differ (an intensity or distance)"),
             ("black_level", black_level, "the colours differ (the colour block")]
    for name, edit, message in cases:
        other = copy_capture(small, work, name, edit)
        out = os.path.join(work, name + "_report")
        code, err = run(clayfit, "report", fit, "-o", out, "--capture", other)
        check(code == 2, f"{name}: exit {code}, expected 2: {err}")
        check("is not the capture the fit was made on" in err and message in err and other in err,
              f"{name}: the message lacks '{message}': {err}")
        check(not os.path.exists(out), f"{name}: a refused capture made a report")
        print(f"{name}: exit {code}: {err.strip()}")


def tree(folder):
    """Every file of a report, report.json without its time of creation."""
    files = {}
    for root, _, names in os.walk(folder):
        for name in names:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                data = f.read()
            if name == "report.json":
                data = b"\n".join(l for l in data.split(b"\n") if b'"created"' not in l)
            files[os.path.relpath(path, folder)] = data
    return files


def leftovers(work, base):
    return [n for n in os.listdir(work)
            if n.startswith(base + ".tmp-") or n.startswith(base + ".old-")]


def folders(clayfit, small, work):
    fit_a = os.path.join(small, "auto", "fit.json")
    fit_b = os.path.join(work, "..", "m0", "fit.json")
    user = os.path.join(work, "user")
    os.makedirs(user)
    with open(os.path.join(user, "thesis.tex"), "w") as f:
        f.write("keep me\n")
    code, err = run(clayfit, "report", fit_a, "-o", user)
    check(code == 2 and "not a clayfit report" in err and "choose another -o" in err,
          f"-o at a user's folder: exit {code}: {err}")
    check(os.listdir(user) == ["thesis.tex"], f"a refused folder changed: {os.listdir(user)}")
    code, err = run(clayfit, "report", fit_a, "-o", os.path.join(user, "thesis.tex"))
    check(code == 2 and "not a folder" in err, f"-o at a file: exit {code}: {err}")

    ref_a, ref_b, out = (os.path.join(work, n) for n in ("a", "b", "report"))
    for fit, ref in ((fit_a, ref_a), (fit_b, ref_b)):
        start = time.monotonic()
        code, err = run(clayfit, "report", fit, "-o", ref)
        seconds = time.monotonic() - start  # the kills fall within a whole run's time
        check(code == 0, f"the report of {fit}: exit {code}: {err}")
    a, b = tree(ref_a), tree(ref_b)
    check(a != b, "the two fits' reports cannot be told apart")
    rng = random.Random(16)
    seen = {"a": 0, "b": 0, "leftover": 0}
    for attempt in range(16):
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(ref_a, out)
        p = subprocess.Popen([clayfit, "--quiet", "report", fit_b, "-o", out],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(rng.uniform(0.0, seconds))
        p.send_signal(signal.SIGKILL)
        p.wait()
        now = tree(out)
        check(now in (a, b), f"killed run {attempt}: {out} is neither report whole")
        seen["a" if now == a else "b"] += 1
        left = leftovers(work, "report")
        check(len(left) <= 1, f"killed run {attempt}: leftovers {left}")
        seen["leftover"] += len(left)
    print("killed runs:", seen)
    code, err = run(clayfit, "report", fit_b, "-o", out)
    check(code == 0 and tree(out) == b, f"the run after the kills: exit {code}: {err}")
    check(leftovers(work, "report") == [], f"the next run left {leftovers(work, 'report')}")


def main():
    case, clayfit, small, work = sys.argv[1:5]
    schema = sys.argv[5] if len(sys.argv) > 5 else None
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    {"oversized": lambda: oversized(clayfit, small, work),
     "capture": lambda: capture(clayfit, small, work, schema),
     "folders": lambda: folders(clayfit, small, work)}[case]()
    print(f"report_safety {case}: {len(FAILURES)} failed")
    return 1 if FAILURES else 0


if __name__ == "__main__":
    sys.exit(main())
