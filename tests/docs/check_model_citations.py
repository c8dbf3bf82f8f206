#!/usr/bin/env python3
"""The model's document and the citations of it (ctest docs_citations).

Fails when
  - a file of the repository (tracked, or untracked and not ignored by git;
    without git: outside .git and the top-level build folder) still names the model document that lived outside the repository (the
    name is assembled below, so that this file does not name it), or
  - a citation "docs/model.md (N)" or "docs/model.md §N.M" names an equation
    or a section that docs/model.md does not have, or
  - docs/model.md's own numbering is broken: equations \\tag{N} not 1, 2, …
    in order, or a section number given twice.

Usage: check_model_citations.py REPOSITORY_ROOT
"""
import os
import re
import sys

from repository import repository_files

OLD_NAME = "MODEL" + ".md"  # the old, out-of-tree document
DOC = os.path.join("docs", "model.md")

CITATION = re.compile(r"docs/model\.md")
# what may follow a citation: (12), (12)–(14), (12, 13), §3, §3.5, joined by
# commas, "and", "to" or dashes
REFERENCE = re.compile(
    r"\s*(?:,|and|to|–|-)?\s*(?:\((\d+(?:\s*[,–-]\s*\d+)*)\)|§\s?(\d+(?:\.\d+)*))")
TAG = re.compile(r"\\tag\{(\d+)\}")
HEADING = re.compile(r"^#{2,6}\s+(\d+(?:\.\d+)*)\.?\s", re.MULTILINE)


def text_files(root):
    for rel in repository_files(root):
        try:
            with open(os.path.join(root, rel), "rb") as f:
                data = f.read()
        except OSError:
            continue  # deleted in the working tree
        if b"\0" in data[:8192]:
            continue  # binary
        yield rel, data.decode("utf-8", errors="replace")


def numbering(doc_text, problems):
    tags = [int(n) for n in TAG.findall(doc_text)]
    if tags != list(range(1, len(tags) + 1)):
        problems.append(f"{DOC}: equations are numbered {tags}, not 1 to {len(tags)} in order")
    sections = HEADING.findall(doc_text)
    for s in sorted(set(sections)):
        if sections.count(s) > 1:
            problems.append(f"{DOC}: section {s} is numbered twice")
    return set(tags), set(sections)


def check_citations(rel, text, equations, sections, problems):
    for m in CITATION.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        at = m.end()
        while True:
            r = REFERENCE.match(text, at)
            if not r:
                break
            at = r.end()
            if r.group(1):
                for n in re.split(r"\s*[,–-]\s*", r.group(1)):
                    if int(n) not in equations:
                        problems.append(f"{rel}:{line}: cites docs/model.md ({n}), "
                                        f"which has equations (1) to ({max(equations, default=0)})")
            else:
                if r.group(2) not in sections:
                    problems.append(f"{rel}:{line}: cites docs/model.md §{r.group(2)}, "
                                    f"which has no such section")


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = sys.argv[1]
    problems = []
    try:
        with open(os.path.join(root, DOC), encoding="utf-8") as f:
            doc_text = f.read()
    except OSError as e:
        print(f"{DOC}: {e}", file=sys.stderr)
        return 1
    equations, sections = numbering(doc_text, problems)
    cited = 0
    for rel, text in text_files(root):
        for number, line in enumerate(text.splitlines(), 1):
            if OLD_NAME in line:
                problems.append(f"{rel}:{number}: names {OLD_NAME}, which is not in the "
                                f"repository: cite {DOC} (its equation or section)")
        check_citations(rel, text, equations, sections, problems)
        cited += len(CITATION.findall(text))
    for p in problems:
        print(p, file=sys.stderr)
    print(f"{len(equations)} equations and {len(sections)} sections in {DOC}; "
          f"{cited} mentions of it checked; {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
