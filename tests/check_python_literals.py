#!/usr/bin/env python3
"""The Python string literals of core/text_escape.h's
text_escape_python_string, read back by Python: each line of the file
test_text_escape writes is the input's bytes in hex, a tab, and the literal.
Asserted: the literal is one string constant (ast), and os.fsencode of its
value (surrogateescape) is the input's bytes.

usage: check_python_literals.py LITERALS.txt
"""
import ast
import os
import sys


def main():
    failures = 0
    with open(sys.argv[1], encoding="ascii") as f:
        lines = f.read().split("\n")[:-1]
    for line in lines:
        hex_bytes, literal = line.split("\t", 1)
        tree = ast.parse(literal, mode="eval")
        if not isinstance(tree.body, ast.Constant) or not isinstance(tree.body.value, str):
            print(f"{literal}: not one string constant")
            failures += 1
            continue
        if os.fsencode(tree.body.value) != bytes.fromhex(hex_bytes):
            print(f"{literal}: reads back as {tree.body.value!r}, not {bytes.fromhex(hex_bytes)!r}")
            failures += 1
    print(f"{len(lines)} literals, {failures} failures")
    return 1 if failures or not lines else 0


if __name__ == "__main__":
    sys.exit(main())
