#!/usr/bin/env python3
"""Validate JSON files against JSON Schemas (2020-12).

usage: validate_json.py FILE=SCHEMA [FILE=SCHEMA ...]
Exit 0 when every file is valid; otherwise print every violation."""
import json
import sys

import jsonschema


def main() -> int:
    failures = 0
    for pair in sys.argv[1:]:
        path, schema_path = pair.split("=", 1)
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
        with open(schema_path, encoding="utf-8") as f:
            schema = json.load(f)
        jsonschema.Draft202012Validator.check_schema(schema)
        errors = list(jsonschema.Draft202012Validator(schema).iter_errors(doc))
        for error in errors:
            print(f"FAIL {path}: {'/'.join(map(str, error.path))}: {error.message}")
        print(f"{path}: {'valid' if not errors else 'INVALID'} against {schema_path}")
        failures += bool(errors)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
