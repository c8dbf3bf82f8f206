"""The repository's files, for the documentation's checks (check_links.py,
check_model_citations.py)."""
import os
import subprocess


def repository_files(root):
    """The repository's files, relative to root: git's tracked and untracked
    ones that are not ignored (so not build/ or out/), or without git every
    file outside .git and the top-level build folder."""
    try:
        listing = subprocess.run(
            ["git", "-C", root, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            capture_output=True, check=True).stdout
        return sorted({name for name in listing.decode("utf-8").split("\0") if name})
    except (OSError, subprocess.CalledProcessError):
        pass
    names = []
    for folder, dirs, files in os.walk(root):
        rel = os.path.relpath(folder, root)
        dirs[:] = [d for d in dirs
                   if d != ".git" and d != "__pycache__" and not (rel == "." and d == "build")]
        names += [os.path.normpath(os.path.join(rel, name)) for name in files]
    return sorted(names)
