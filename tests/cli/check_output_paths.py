#!/usr/bin/env python3
"""Bad output locations are refused before any work, with exit 2 and a reason.

usage: check_output_paths.py CLAYFIT COMMAND WORKDIR

COMMAND is fit, report, export, synth, inspect, lights or bench (bench fit's
--work and --json). Each case runs the command with valid inputs and one bad
output path and checks: exit status 2, the message (the option, the path
and why), and that nothing was done first: stderr is that one line, with no
progress line of loading, fitting or rendering (the commands run without
--quiet). One good path per command (missing parent folders are created)
must still work, and export writes to a FIFO that a process reads (one
that none reads is refused: the write would wait forever). The read-only folder case is skipped as root, for whom
it is writable; the path under a regular file and the one in /proc fail
for root too.
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import threading
import zlib

FOLDER_CASES = [
    ("", r"^-o: the path is empty$"),
    ("somefile", r"^-o 'somefile': exists and is not a folder \(Not a directory\)$"),
    ("somefile/sub", r"^-o 'somefile/sub': 'somefile' is not a folder \(Not a directory\)$"),
    ("/proc/clayfit-out/sub", r"^-o '/proc/clayfit-out/sub': cannot (create a file in|write into) "
     r"the folder '/proc': .+$"),
    ("ro/sub", r"^-o 'ro/sub': cannot write into the folder 'ro': Permission denied$"),
]
# a folder written into (not replaced as a whole, as the report's is)
INTO_CASES = FOLDER_CASES + [
    ("ro", r"^-o 'ro': cannot write into the folder 'ro': Permission denied$")]
FILE_CASES = [
    ("", r"^-o: the path is empty$"),
    ("adir", r"^-o 'adir': is a folder; a file is expected \(Is a directory\)$"),
    ("adir/", r"^-o 'adir/': names a folder; a file is expected$"),
    ("somefile/x.json", r"^-o 'somefile/x.json': 'somefile' is not a folder \(Not a directory\)$"),
    ("missing/x.json", r"^-o 'missing/x.json': the folder 'missing' cannot be used: "
     r"No such file or directory$"),
    ("/proc/clayfit-out.json", r"^-o '/proc/clayfit-out.json': cannot (create a file in|write "
     r"into) the folder '/proc': .+$"),
    ("ro/x.json", r"^-o 'ro/x.json': cannot write into the folder 'ro': Permission denied$"),
    ("fifo", r"^-o 'fifo': a FIFO that no process is reading; clayfit would wait for a reader "
     r"forever \(start the reader first, or name a regular file\)$"),
]


def run(command, cwd):
    return subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=300)


def check_fifo_read(command, work):
    """A FIFO that a process reads is written: export -o FIFO, the reader gets the JSON."""
    received = []
    reader = threading.Thread(target=lambda: received.append(
        open(os.path.join(work, "fifo"), "rb").read()))
    reader.start()
    result = run(command("fifo"), work)
    reader.join(timeout=60)
    ok = result.returncode == 0 and received and received[0].lstrip().startswith(b"{")
    print(f"{'ok' if ok else 'FAIL'} a FIFO with a reader: exit {result.returncode}, "
          f"{len(received[0]) if received else 0} bytes read")
    return [] if ok else [f"a FIFO with a reader: exit {result.returncode}: {result.stderr[-300:]}"]


def write_grey_png(path, width, height, grey):
    """An 8-bit grey PNG of grey(x, y) in 0..255, by hand (no imaging module)."""
    rows = b"".join(b"\0" + bytes(grey(x, y) for x in range(width)) for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def write_chrome_ball(work):
    """A 64x48 photo of a dark ball (radius 16) with one clipped highlight, and its mask."""
    def inside(x, y, r):
        return (x + 0.5 - 32) ** 2 + (y + 0.5 - 24) ** 2 <= r * r
    write_grey_png(os.path.join(work, "chrome.png"), 64, 48,
                   lambda x, y: 255 if (x - 36) ** 2 + (y - 20) ** 2 <= 2 else
                   (20 if inside(x, y, 16) else 90))
    write_grey_png(os.path.join(work, "chrome_mask.png"), 64, 48,
                   lambda x, y: 255 if inside(x, y, 16) else 0)


def setup(clayfit, work):
    """A tiny capture and its fit, a regular file, a folder, a read-only folder."""
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.join(work, "adir"))
    os.makedirs(os.path.join(work, "fitdir", "fit.json"))  # a folder where fit.json goes
    os.makedirs(os.path.join(work, "ro"))
    os.mkfifo(os.path.join(work, "fifo"))  # no process reads these two
    os.makedirs(os.path.join(work, "fifodir"))
    os.mkfifo(os.path.join(work, "fifodir", "fit.json"))
    os.chmod(os.path.join(work, "ro"), 0o555)
    with open(os.path.join(work, "somefile"), "w", encoding="utf-8") as f:
        f.write("a file\n")
    write_chrome_ball(work)
    for command in (["synth", "-o", "capture", "--model", "M0", "--images", "3", "--size", "64x48",
                     "--format", "exr", "--supersample", "1"],
                    ["fit", "capture/capture.json", "-o", "fit", "--model", "M0",
                     "--footprint", "centre", "--no-multistart"]):
        result = run([clayfit, "--quiet"] + command, work)
        if result.returncode != 0:
            sys.exit(f"setup failed: {' '.join(command)}: {result.stderr}")


def commands(clayfit, name):
    """(the command for an output path, its option, file or folder cases)"""
    capture, fit = "capture/capture.json", "fit/fit.json"
    table = {
        "fit": (lambda o: [clayfit, "fit", capture, "-o", o, "--model", "M0"], "-o", INTO_CASES +
                [("fitdir", r"^-o 'fitdir/fit.json': is a folder; a file is expected"),
                 ("fifodir", r"^-o 'fifodir/fit.json': a FIFO that no process is reading")]),
        "report": (lambda o: [clayfit, "report", fit, "-o", o], "-o", FOLDER_CASES),
        "export": (lambda o: [clayfit, "export", fit, "--format", "json", "-o", o], "-o",
                   FILE_CASES),
        "synth": (lambda o: [clayfit, "synth", "-o", o, "--images", "2", "--size", "32x24",
                             "--supersample", "1"], "-o", INTO_CASES),
        "inspect": (lambda o: [clayfit, "inspect", capture, "-o", o], "-o", INTO_CASES),
        "lights": (lambda o: [clayfit, "lights", "chrome.png", "--mask", "chrome_mask.png", "-o", o],
                   "-o", INTO_CASES),
        "bench-work": (lambda o: [clayfit, "bench", "fit", "--sizes", "2x48x36", "--budgets", "100", "--model", "M0",
                                  "--work", o], "--work", INTO_CASES),
        "bench-json": (lambda o: [clayfit, "bench", "fit", "--sizes", "2x48x36", "--budgets", "100", "--model", "M0",
                                  "--work", "bench", "--json", o], "--json", FILE_CASES),
    }
    return table[name]


# the good path of each: missing parent folders are created (not for a file)
GOOD = {"fit": "new/parents/fit", "report": "new/parents/report", "export": "adir/preset.json",
        "synth": "new/parents/synth", "inspect": "new/parents/overlays",
        "lights": "new/parents/lights"}


def main():
    clayfit, name, work = sys.argv[1], sys.argv[2], os.path.abspath(sys.argv[3])
    setup(clayfit, work)
    command, option, cases = commands(clayfit, name)
    program = "bench" if name.startswith("bench") else name
    failures, checked = [], 0
    for path, pattern in cases:
        if path.split("/")[0] == "ro" and os.geteuid() == 0:
            print(f"skipped {path!r}: running as root, a read-only folder is writable")
            continue
        if path.startswith("/proc/") and not os.path.isdir("/proc"):
            print(f"skipped {path!r}: no /proc")
            continue
        result = run(command(path), work)
        checked += 1
        lines = result.stderr.splitlines()
        prefix = f"clayfit {program}: "
        message = lines[0][len(prefix):] if lines and lines[0].startswith(prefix) else None
        expected = pattern.replace("^-o", "^" + re.escape(option), 1)
        why = []
        if result.returncode != 2:
            why.append(f"exit status {result.returncode}, expected 2")
        if message is None or not re.search(expected, message):
            why.append(f"message does not match /{expected}/")
        if len(lines) != 1 or "\r" in result.stderr:
            why.append("more than the message on stderr: some work was done first")
        print(f"{'FAIL' if why else 'ok'} {program} {option} {path!r}: exit {result.returncode}, "
              f"stderr {result.stderr.strip()[:300]!r}")
        failures += [f"{path!r}: {w}" for w in why]
    if name in GOOD:
        result = run(command(GOOD[name]), work)
        checked += 1
        print(f"good path {GOOD[name]!r}: exit {result.returncode}")
        if result.returncode != 0:
            failures.append(f"good path {GOOD[name]!r}: exit {result.returncode}: "
                            f"{result.stderr.strip()[-300:]}")
    if name == "export":
        failures += check_fifo_read(command, work)
        checked += 1
    os.chmod(os.path.join(work, "ro"), 0o755)
    for failure in failures:
        print("FAIL:", failure)
    print(f"{checked} cases, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
