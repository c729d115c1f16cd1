#!/usr/bin/env python3
"""Every path that README.md, docs/*.md and the folders' README.md files name
must exist: relative Markdown links, and `code` spans that start with one of
the project's top-level folders (kernel/, app/, platform/, ...). Globs (*) must
match something and {a,b} alternatives must each exist; spans under build/ or
with placeholders (<...>, NAME, FILE) are outputs or patterns, not paths.

Usage: paths_exist.py SOURCE_DIR        (exit 1 and a list when any is missing)
       paths_exist.py --self-test       (a missing path must be caught)
"""
import glob
import pathlib
import re
import sys
import tempfile

TOP = ("kernel/", "app/", "platform/", "hdl/", "hil/", "tools/", "tests/", "toolchains/", "docs/", ".ci/")
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
CODE = re.compile(r"`([^`\s]+)`")
PLACEHOLDER = re.compile(r"<|>|\b[A-Z]{2,}\b|\.\.\.|…|\$")


def expand(path):
    """'a/{b,c}.hpp' -> ['a/b.hpp', 'a/c.hpp'] (one level of braces)."""
    m = re.search(r"\{([^{}]*)\}", path)
    if not m:
        return [path]
    return [p for alt in m.group(1).split(",") for p in expand(path[:m.start()] + alt + path[m.end():])]


def exists(base, path):
    path = path.rstrip(".,;:")
    if "*" in path or "?" in path:
        return bool(glob.glob(str(base / path)))
    return (base / path).exists()


def documents(root):
    docs = [root / "README.md"] + sorted((root / "docs").glob("*.md"))
    docs += sorted(p for p in root.glob("*/**/README.md") if "build" not in p.relative_to(root).parts[:1])
    return [d for d in docs if d.exists()]


def check(root):
    missing = []
    for doc in documents(root):
        text = doc.read_text(encoding="utf-8")
        for lineno, line in enumerate(text.splitlines(), 1):
            for target in LINK.findall(line):
                if re.match(r"[a-z]+:", target):  # a URL or mailto:
                    continue
                for p in expand(target):
                    if not exists(doc.parent, p):
                        missing.append(f"{doc.relative_to(root)}:{lineno}: link {p}")
            for span in CODE.findall(line):
                if not span.startswith(TOP) or PLACEHOLDER.search(span):
                    continue
                span = span.split(":")[0]  # file.cpp:123 names a line of the file
                for p in expand(span):
                    if not exists(root, p):
                        missing.append(f"{doc.relative_to(root)}:{lineno}: `{p}`")
    return missing


def self_test():
    with tempfile.TemporaryDirectory() as d:
        root = pathlib.Path(d)
        (root / "kernel/src").mkdir(parents=True)
        (root / "kernel/src/voter.cpp").write_text("")
        (root / "README.md").write_text("See `kernel/src/voter.cpp`, `kernel/src/{voter,gone}.cpp` and [x](kernel/src/lost.cpp).\n")
        missing = check(root)
    ok = len(missing) == 2 and any("gone.cpp" in m for m in missing) and any("lost.cpp" in m for m in missing)
    print("self-test:", "PASS" if ok else f"FAIL ({missing})")
    return 0 if ok else 1


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    if sys.argv[1] == "--self-test":
        return self_test()
    root = pathlib.Path(sys.argv[1]).resolve()
    missing = check(root)
    for m in missing:
        print(f"missing: {m}")
    print(f"{len(documents(root))} documents checked: " + ("PASS" if not missing else f"FAIL, {len(missing)} missing"))
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
