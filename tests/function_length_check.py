#!/usr/bin/env python3
"""Short rooms: no function over MAX_FUNCTION_LINES lines and no source file
over MAX_FILE_LINES lines in kernel/, app/, platform/, hdl/sim, hil/ and
tools/ (tests and generated code aside). Function extents come from
universal-ctags (--fields=+ne: a definition's first and last line).

The functions and files listed in tests/function_length_allowlist.txt are
those still over the limit when the check was written: a ratchet. One that
shrinks under the limit must leave the list (the check says so), and nothing
may join it.

Usage: function_length_check.py SOURCE_DIR
       function_length_check.py --self-test
"""
import json
import re
import pathlib
import subprocess
import sys
import tempfile

MAX_FUNCTION_LINES = 120
MAX_FILE_LINES = 600
FOLDERS = ["kernel", "app", "platform", "hdl/sim", "hil", "tools"]
SUFFIXES = {".cpp", ".hpp", ".h", ".cc"}


def sources(root):
    for folder in FOLDERS:
        for p in sorted((root / folder).rglob("*")):
            if p.suffix in SUFFIXES and p.is_file():
                yield p


def long_functions(root, files):
    out = subprocess.run(["ctags", "--output-format=json", "--fields=+ne", "--kinds-C++=f", "--languages=C++",
                          "--language-force=C++", "-f", "-"] + [str(f) for f in files],
                         check=True, capture_output=True, text=True).stdout
    found = {}
    for line in out.splitlines():
        tag = json.loads(line)
        if "end" not in tag:
            continue
        n = tag["end"] - tag["line"] + 1
        if n > MAX_FUNCTION_LINES:
            rel = pathlib.Path(tag["path"]).resolve().relative_to(root)
            name = (tag.get("scope", "") + "::" if tag.get("scope") else "") + tag["name"]
            name = re.sub(r"__anon[0-9a-f]+", "{anonymous}", name)  # ctags numbers anonymous namespaces
            found[f"function {rel} {name}"] = n
    return found


def long_files(root, files):
    found = {}
    for f in files:
        n = sum(1 for _ in f.open(encoding="utf-8", errors="replace"))
        if n > MAX_FILE_LINES:
            found[f"file {f.relative_to(root)}"] = n
    return found


def check(root, allowlist_path):
    files = list(sources(root))
    over = {**long_functions(root, files), **long_files(root, files)}
    allowed = set()
    if allowlist_path.exists():
        for line in allowlist_path.read_text().splitlines():
            line = line.split("#")[0].strip()
            if line:
                allowed.add(line)
    problems = []
    for key, n in sorted(over.items()):
        if key not in allowed:
            problems.append(f"{key}: {n} lines (limit {MAX_FUNCTION_LINES if key.startswith('function') else MAX_FILE_LINES})")
    for key in sorted(allowed - set(over)):
        problems.append(f"{key}: now within the limit or gone: remove it from {allowlist_path.name}")
    return over, allowed, problems


def self_test():
    with tempfile.TemporaryDirectory() as d:
        root = pathlib.Path(d)
        (root / "kernel/src").mkdir(parents=True)
        body = "\n".join(f"  x += {i};" for i in range(MAX_FUNCTION_LINES))
        (root / "kernel/src/a.cpp").write_text(f"int f() {{\n  int x = 0;\n{body}\n  return x;\n}}\nint g() {{ return 1; }}\n")
        _, _, problems = check(root, root / "allow.txt")
        (root / "allow.txt").write_text("function kernel/src/a.cpp f\nfunction kernel/src/a.cpp gone\n")
        _, _, problems2 = check(root, root / "allow.txt")
    ok = (len(problems) == 1 and "kernel/src/a.cpp f" in problems[0] and len(problems2) == 1 and "gone" in problems2[0])
    print("self-test:", "PASS" if ok else f"FAIL ({problems}, {problems2})")
    return 0 if ok else 1


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    if sys.argv[1] == "--self-test":
        return self_test()
    root = pathlib.Path(sys.argv[1]).resolve()
    over, allowed, problems = check(root, root / "tests/function_length_allowlist.txt")
    for key, n in sorted(over.items()):
        print(f"{'allowed ' if key in allowed else ''}{key}: {n} lines")
    for p in problems:
        print(f"FAIL: {p}")
    print(f"{len(over)} over the limits, {len(allowed)} on the allowlist: " + ("PASS" if not problems else "FAIL"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
