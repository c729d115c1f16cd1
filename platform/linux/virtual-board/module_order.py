#!/usr/bin/env python3
"""Prints the kernel modules to insmod, dependencies first, for the given
module names. Reads each module's .modinfo 'depends=' field directly (no
depmod needed on the build host).

usage: module_order.py MODULE_DIR [MODULE_DIR ...] -- NAME [NAME ...]
"""
import pathlib
import re
import sys


def main():
    argv = sys.argv[1:]
    if "--" not in argv:
        print(__doc__, file=sys.stderr)
        return 2
    split = argv.index("--")
    dirs, names = argv[:split], argv[split + 1:]
    files = {}
    for d in dirs:
        for ko in pathlib.Path(d).rglob("*.ko"):
            files.setdefault(ko.stem.replace("-", "_"), ko)
    order, seen = [], set()

    def visit(name, chain):
        key = name.replace("-", "_")
        if key in seen:
            return
        if key in chain:
            raise SystemExit(f"module dependency cycle: {' -> '.join(chain + [key])}")
        if key not in files:
            raise SystemExit(f"module {name} not found under {dirs}")
        m = re.search(rb"(?:^|\x00)depends=([^\x00]*)", files[key].read_bytes())
        for dep in filter(None, (m.group(1).decode() if m else "").split(",")):
            visit(dep, chain + [key])
        seen.add(key)
        order.append(files[key])

    for n in names:
        visit(n, [])
    for f in order:
        print(f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
