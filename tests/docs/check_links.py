#!/usr/bin/env python3
"""The documentation's links and doc paths (ctest docs_links).

Fails when
  - a relative Markdown link in README.md, docs/ or bench/*.md names a file
    that does not exist, or an anchor (#section) that the target Markdown file
    has no heading for (GitHub's anchors: the heading in lower case, without
    punctuation, spaces as hyphens, -1, -2, ... for repeats), or
  - a file of the repository (tracked, or untracked and not ignored by git)
    names a document docs/<name>.md (or docs/studies/<name>.md) that does not
    exist, or
  - a study in docs/studies/ is not dated (its file name begins with the date,
    YYYY-MM-DD-, and its first five lines hold that date) or is missing from
    the index docs/studies/README.md.

Links inside code (fenced blocks and `spans`) are not links and are skipped,
as are absolute URLs.

Usage: check_links.py REPOSITORY_ROOT
       check_links.py --self-test    (a made-up tree with one of each fault
                                      must give exactly those problems)
"""
import os
import re
import sys
import tempfile

from repository import repository_files

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
DOC_PATH = re.compile(r"(?<![\w./-])docs/(?:[\w.-]+/)*[\w.-]+\.md\b")
FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^ {0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
STUDY = re.compile(r"^(\d{4}-\d{2}-\d{2})-[\w.-]+\.md$")
STUDIES = os.path.join("docs", "studies")


def read_text(path):
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None  # deleted in the working tree
    if b"\0" in data[:8192]:
        return None  # binary
    return data.decode("utf-8", errors="replace")


def prose_lines(text):
    """(line number, line) outside fenced code, with `code spans` blanked."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, re.sub(r"`[^`]*`", "``", line)


def slug(heading):
    """GitHub's anchor for a heading."""
    text = re.sub(r"`", "", heading)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link's text only
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def raw_headings(text):
    """Headings with their code spans (prose_lines blanks them)."""
    fenced = False
    for line in text.splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            m = HEADING.match(line)
            if m:
                yield m.group(2)


def anchor_set(text):
    seen = {}
    result = set()
    for heading in raw_headings(text):
        base = slug(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        result.add(base if n == 0 else f"{base}-{n}")
    return result


def check_markdown_links(root, rel, text, problems, cache):
    folder = os.path.dirname(rel)
    count = 0
    for number, line in prose_lines(text):
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
                continue  # http:, https:, mailto:
            count += 1
            path, _, anchor = target.partition("#")
            resolved = os.path.normpath(os.path.join(folder, path)) if path else rel
            full = os.path.join(root, resolved)
            if not os.path.exists(full):
                problems.append(f"{rel}:{number}: links to {target}: {resolved} does not exist")
                continue
            if anchor and resolved.endswith(".md"):
                if resolved not in cache:
                    cache[resolved] = anchor_set(read_text(full) or "")
                if anchor not in cache[resolved]:
                    problems.append(f"{rel}:{number}: links to {target}: {resolved} has no "
                                    f"heading whose anchor is #{anchor}")
    return count


def check_studies(root, problems):
    folder = os.path.join(root, STUDIES)
    if not os.path.isdir(folder):
        return 0
    index = read_text(os.path.join(folder, "README.md")) or ""
    studies = 0
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".md") or name == "README.md":
            continue
        studies += 1
        rel = os.path.join(STUDIES, name)
        m = STUDY.match(name)
        if not m:
            problems.append(f"{rel}: a study's name begins with its date, YYYY-MM-DD-")
            continue
        head = "\n".join((read_text(os.path.join(folder, name)) or "").splitlines()[:5])
        if m.group(1) not in head:
            problems.append(f"{rel}: its first five lines do not give its date, {m.group(1)}")
        if f"({name})" not in index:
            problems.append(f"{rel}: not in the index, {STUDIES}/README.md")
    return studies


def check(root):
    """(problems, links, doc paths, studies) of the tree at root."""
    problems = []
    cache = {}
    links = paths = 0
    for rel in repository_files(root):
        if os.path.realpath(os.path.join(root, rel)) == os.path.realpath(__file__):
            continue  # this file: its self-test names documents that do not exist
        text = read_text(os.path.join(root, rel))
        if text is None:
            continue
        markdown = rel.endswith(".md") and (
            rel == "README.md" or rel.startswith("docs" + os.sep) or
            (rel.startswith("bench" + os.sep) and rel.count(os.sep) == 1))
        if markdown:
            links += check_markdown_links(root, rel, text, problems, cache)
        for number, line in enumerate(text.splitlines(), 1):
            for m in DOC_PATH.finditer(line):
                paths += 1
                if not os.path.exists(os.path.join(root, m.group(0))):
                    problems.append(f"{rel}:{number}: names {m.group(0)}, which does not exist")
    studies = check_studies(root, problems)
    return problems, links, paths, studies


SELF_TEST = {
    "README.md": "See [the fit](docs/fit.md#the-model-choice---model-auto), "
                 "[gone](docs/gone.md), [no such part](docs/fit.md#nowhere), "
                 "`[code](nowhere.md)` and [the web](https://example.org/x.md).\n",
    "docs/fit.md": "# Fit\n\n## The model choice (`--model auto`)\n\n"
                   "Cites docs/fit.md and docs/missing.md.\n\n```\n[fenced](nowhere.md)\n```\n",
    "docs/studies/README.md": "| [a](2026-01-02-a.md) |\n",
    "docs/studies/2026-01-02-a.md": "# A\n\n*Study of 2026-01-02.*\n",
    "docs/studies/2026-01-03-b.md": "# B, undated in its text and not in the index\n",
    "docs/studies/c.md": "# C, no date in its name\n",
}
SELF_TEST_PROBLEMS = [
    "README.md:1: links to docs/gone.md",
    "README.md:1: names docs/gone.md",
    "README.md:1: links to docs/fit.md#nowhere",
    "docs/fit.md:5: names docs/missing.md",
    "docs/studies/2026-01-03-b.md: its first five lines",
    "docs/studies/2026-01-03-b.md: not in the index",
    "docs/studies/c.md: a study's name",
]


def self_test():
    with tempfile.TemporaryDirectory() as root:
        for rel, text in SELF_TEST.items():
            os.makedirs(os.path.join(root, os.path.dirname(rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        problems = check(root)[0]
    missed = [want for want in SELF_TEST_PROBLEMS
              if not any(p.startswith(want) for p in problems)]
    extra = [p for p in problems
             if not any(p.startswith(want) for want in SELF_TEST_PROBLEMS)]
    for p in problems:
        print(f"found: {p}")
    for m in missed:
        print(f"not found: {m}", file=sys.stderr)
    for e in extra:
        print(f"found but not a fault: {e}", file=sys.stderr)
    print(f"self-test: {len(problems)} problems found, {len(SELF_TEST_PROBLEMS)} expected")
    return 1 if missed or extra or len(problems) != len(SELF_TEST_PROBLEMS) else 0


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    if sys.argv[1] == "--self-test":
        return self_test()
    problems, links, paths, studies = check(sys.argv[1])
    for p in problems:
        print(p, file=sys.stderr)
    print(f"{links} relative links and {paths} doc paths checked, {studies} studies; "
          f"{len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
