#!/usr/bin/env python3
"""Run one clayfit command and check what it did.

usage: check_cli.py [--exit N] [--stderr REGEX] [--stdout REGEX]
                    [--stdout-not REGEX] [--cwd DIR] [--schema FILE]
                    [--json-file PATH] [--expect PYTHON_EXPRESSION]
                    -- COMMAND ARGS...

--exit     the exit status the command must return (default 0)
--stderr   a regular expression stderr must contain
--stdout   a regular expression stdout must contain (repeatable)
--stdout-not  a regular expression stdout must not contain (repeatable)
--cwd      the folder the command runs in (default: the current one)
--schema   stdout must be JSON valid against this JSON Schema (2020-12)
--json-file  the JSON to check is this file (written by the command), not stdout
--expect   a Python expression over `doc` (stdout's JSON), with json, math and os, that
           must be true
--skip-unless PATH  exit 77 (skipped) when PATH does not exist (third-party data)
"""
import argparse
import json
import math  # noqa: F401  (for --expect expressions)
import os  # noqa: F401  (for --expect expressions)
import re
import subprocess
import sys

import jsonschema


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--exit", type=int, default=0)
    parser.add_argument("--stderr")
    parser.add_argument("--stdout", action="append", default=[])
    parser.add_argument("--stdout-not", action="append", default=[])
    parser.add_argument("--cwd")
    parser.add_argument("--schema")
    parser.add_argument("--json-file")
    parser.add_argument("--expect", action="append", default=[])
    parser.add_argument("--skip-unless")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    if args.skip_unless and not os.path.exists(args.skip_unless):
        print(f"skipped: {args.skip_unless} is absent")
        return 77
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    result = subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=args.cwd)
    failures = []
    if result.returncode != args.exit:
        failures.append(f"exit status {result.returncode}, expected {args.exit}")
    if args.stderr and not re.search(args.stderr, result.stderr):
        failures.append(f"stderr does not match /{args.stderr}/")
    for pattern in args.stdout:
        if not re.search(pattern, result.stdout):
            failures.append(f"stdout does not match /{pattern}/")
    for pattern in args.stdout_not:
        if re.search(pattern, result.stdout):
            failures.append(f"stdout matches /{pattern}/")
    if result.returncode < 0 or "Sanitizer" in result.stderr:
        failures.append("the command crashed or a sanitizer reported an error")
    doc = None
    if args.schema or args.expect:
        try:
            if args.json_file:
                with open(args.json_file, encoding="utf-8") as f:
                    doc = json.load(f)
            else:
                doc = json.loads(result.stdout)
        except (OSError, json.JSONDecodeError) as error:
            failures.append(f"{args.json_file or 'stdout'} is not JSON: {error}")
    if doc is not None and args.schema:
        with open(args.schema, encoding="utf-8") as f:
            schema = json.load(f)
        validator = jsonschema.Draft202012Validator(schema)
        for error in validator.iter_errors(doc):
            failures.append(f"schema: {'/'.join(map(str, error.path))}: {error.message}")
    if doc is not None:
        for expression in args.expect:
            if not eval(expression, {"doc": doc, "json": json, "math": math, "os": os}):  # noqa: S307
                failures.append(f"expectation failed: {expression}")
    print("$", " ".join(command))
    print("exit", result.returncode)
    if args.stdout or args.stdout_not:
        print("stdout:", result.stdout.strip()[:2000])
    if result.stderr:
        print("stderr:", result.stderr.strip()[:2000])
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
