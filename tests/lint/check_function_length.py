#!/usr/bin/env python3
"""Functions over 80 lines in the C and C++ sources (docs/design.md: a
function over about 80 lines is split into named steps).

Usage: check_function_length.py ROOT [--limit N] [DIR ...]

Scans every .c, .h, .cpp and .hpp file under ROOT's src/, bench/ and tools/
(or the DIRs given, relative to ROOT). The sources are clang-formatted
(.clang-format), so a function's signature starts at column 0 and its body
ends with a `}` alone at column 0; a C++ member function defined in its
class (a class or struct opened at column 0) starts at column 2 and ends
with `  }`. A function's length counts its lines from the signature's first
line to that closing brace. Prints each function over the limit as
file:line: name, N lines, and exits 1 if there is any; 0 otherwise.
"""
import argparse
import os
import re
import sys

EXTENSIONS = (".c", ".h", ".cpp", ".hpp")
DEFAULT_DIRS = ("src", "bench", "tools")
# Lines that open something other than a function at their indentation.
NOT_A_FUNCTION = re.compile(
    r"^\s*(typedef|struct|union|enum|class|namespace|extern\s+\"C\"\s*\{|if|else|for|while|"
    r"do|switch|case|default|return|template\s*<[^>]*>\s*$)\b")
# The line that opens a function's body: its parameter list's ')' (a
# member function's qualifiers, a constructor's initialisers) and '{'.
BODY_OPENS = re.compile(r"\)(\s*(const|override|final|noexcept))*\s*\{$")
NAME = re.compile(r"([A-Za-z_][A-Za-z_0-9:~]*)\s*\(")


def strip_comments(lines):
    """The lines with comments and string literals blanked (the line count
    and the columns kept), so that braces and parentheses in them never
    count."""
    out, in_block = [], False
    for line in lines:
        text, i, n = [], 0, len(line)
        while i < n:
            if in_block:
                end = line.find("*/", i)
                if end < 0:
                    i = n
                else:
                    i, in_block = end + 2, False
                continue
            c = line[i]
            if line.startswith("/*", i):
                in_block, i = True, i + 2
                text.append(" ")
            elif line.startswith("//", i):
                break
            elif c in "\"'":
                j = i + 1
                while j < n and line[j] != c:
                    j += 2 if line[j] == "\\" else 1
                text.append(c + " " * max(0, min(j, n) - i - 1) + (c if j < n else ""))
                i = j + 1
            else:
                text.append(c)
                i += 1
        out.append("".join(text).rstrip())
    return out


def is_signature(line, indent):
    """True when `line` (comments blanked) may begin a function definition
    at `indent` spaces: an identifier there, a '(' before any '=', and
    none of the keywords that open something else."""
    if len(line) - len(line.lstrip(" ")) != indent or not line.strip():
        return False
    first = line[indent]
    if not (first.isalpha() or first == "_" or first == "~"):
        return False
    if NOT_A_FUNCTION.match(line):
        return False
    paren = line.find("(")
    equals = line.find("=")
    if paren < 0 or (0 <= equals < paren):
        return False
    return True


def functions(lines, indent, begin, end):
    """(first line, last line, name) of each function defined at `indent`
    in lines[begin:end] (0-based, inclusive ends)."""
    found, i = [], begin
    closing = " " * indent + "}"
    while i < end:
        line = lines[i]
        if line.startswith("#"):  # the preprocessor, with its continuations
            while i < end and lines[i].endswith("\\"):
                i += 1
            i += 1
            continue
        if not is_signature(line, indent):
            i += 1
            continue
        # the signature runs to the line that opens the body; a ';' first
        # makes it a declaration
        j = i
        while j < end and lines[j].strip() and not lines[j].startswith("#") and \
                not lines[j].endswith(("{", ";", "{}")):
            j += 1
        if j >= end or not BODY_OPENS.search(lines[j]):
            i = j + 1
            continue
        match = NAME.search(lines[i])
        name = match.group(1) if match else "?"
        k = j + 1
        while k < end and lines[k] != closing:
            k += 1
        if k >= end:
            i = j + 1
            continue
        found.append((i, k, name))
        i = k + 1
    return found


def class_bodies(lines):
    """(begin, end) of each class or struct body opened at column 0 (a C++
    member function is defined at column 2 in it)."""
    bodies, i = [], 0
    while i < len(lines):
        if re.match(r"^(class|struct)\b[^;]*\{$", lines[i]):
            k = i + 1
            while k < len(lines) and not lines[k].startswith("}"):
                k += 1
            bodies.append((i + 1, k))
            i = k
        i += 1
    return bodies


def scan_text(text, cpp, limit):
    """(line, length, name) of each function over `limit` lines in a
    source's text (cpp: C++, with member functions)."""
    lines = strip_comments(text.split("\n"))
    found = functions(lines, 0, 0, len(lines))
    if cpp:
        for begin, end in class_bodies(lines):
            found += functions(lines, 2, begin, end)
    return sorted((first + 1, last - first + 1, name) for first, last, name in found
                  if last - first + 1 > limit)


def self_check():
    """The scanner on made-up sources: a C function and a C++ member
    function of 81 lines found, at their first line, and one of 80 lines,
    a declaration, a table and a one-line function not."""
    body = lambda n: "".join(f"  x += {k}; /* {{ */\n" for k in range(n))
    c = ("/* a comment */\nint table[] = {\n  1,\n};\nint declared(int x);\n"
         "static int fits(int x) {\n" + body(78) + "}\n"
         "void one_line(void) {}\n"
         "static int\nlong_one(int x,\n         int y) {\n" + body(78) + "}\n")
    cpp = ("namespace {\nclass A {\n public:\n  int fits(int x) const {\n" + body(78) +
           "  }\n  int long_one(int x) {\n" + body(79) + "  }\n};\n}  // namespace\n")
    first = lambda text: text.split("\n").index(next(
        line for line in text.split("\n") if "long_one(" in line)) + 1
    expect_c, expect_cpp = [(first(c), 81, "long_one")], [(first(cpp), 81, "long_one")]
    got_c, got_cpp = scan_text(c, False, 80), scan_text(cpp, True, 80)
    if got_c != expect_c or got_cpp != expect_cpp:
        print(f"the scanner is broken: found {got_c} and {got_cpp}, expected {expect_c} "
              f"and {expect_cpp}")
        return False
    return True


def scan(path, limit):
    with open(path, encoding="utf-8", errors="replace") as f:
        return scan_text(f.read(), path.endswith((".cpp", ".hpp")), limit)


def sources(root, dirs):
    """The C and C++ files under root's dirs (or the files given)."""
    for d in dirs:
        top = os.path.join(root, d)
        if os.path.isfile(top):
            yield top
        for base, subdirs, names in os.walk(top):
            subdirs.sort()
            yield from (os.path.join(base, n) for n in sorted(names) if n.endswith(EXTENSIONS))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("root")
    parser.add_argument("dirs", nargs="*", default=list(DEFAULT_DIRS))
    parser.add_argument("--limit", type=int, default=80)
    args = parser.parse_args()
    if not self_check():
        return 1
    offenders, files = [], 0
    for path in sources(args.root, args.dirs):
        files += 1
        for line, length, function in scan(path, args.limit):
            offenders.append((os.path.relpath(path, args.root), line, length, function))
    for path, line, length, function in offenders:
        print(f"{path}:{line}: {function}, {length} lines (limit {args.limit})")
    print(f"{files} files, {len(offenders)} functions over {args.limit} lines")
    return 1 if offenders else 0


if __name__ == "__main__":
    sys.exit(main())
