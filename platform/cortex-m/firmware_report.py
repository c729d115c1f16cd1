#!/usr/bin/env python3
"""Worst-case stack and memory use of the Cortex-M firmware.

Usage: firmware_report.py --build DIR --map FIRMWARE.map [--flash-budget BYTES] [--ram-budget BYTES]
       firmware_report.py --self-test

Stack: reads the call graphs GCC writes with -fcallgraph-info=su (one .ci
file per object under DIR), joins them across files and computes, for the
firmware entry (Reset_Handler) and every kernel entry point, the deepest
chain of frames. Fails on recursion (a cycle), on a frame GCC marks dynamic
or bounded (alloca/VLA), on an indirect call, and when the firmware's worst
case plus the exception allowance exceeds the stack reserved in firmware.ld
(the map's .stack section).
Library leaves (memcpy, memset, memcmp: newlib's are leaf functions using no
stack beyond pushed registers) count as kLibraryLeafBytes.

Memory: flash and RAM used, from the linker map's output sections, and the
share of flash taken by the embedded table, test vectors and session vectors.
Exit status 0 when everything is within budget, 1 otherwise.
"""
import argparse
import pathlib
import re
import sys

kLibraryLeafBytes = 32      # pushed registers of a newlib string routine
kExceptionFrameBytes = 104  # a fault taken at the deepest point: FP context frame (26 words)

NODE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
FRAME = re.compile(r'\\n(\d+) bytes \((static|dynamic|dynamic,bounded)\)')


def load_graph(build_dir):
    frames, names, edges, kinds = {}, {}, {}, {}
    for ci in sorted(pathlib.Path(build_dir).rglob("*.ci")):
        text = ci.read_text()
        for title, label in NODE.findall(text):
            m = FRAME.search(label)
            names.setdefault(title, label.split("\\n")[0])
            if m:  # a definition (declarations have no frame)
                frames[title] = int(m.group(1))
                kinds[title] = m.group(2)
                names[title] = label.split("\\n")[0]
        for src, dst in EDGE.findall(text):
            edges.setdefault(src, set()).add(dst)
    return frames, names, edges, kinds


def resolve(title, frames):
    """A call to an external symbol names it without the defining file's prefix."""
    if title in frames:
        return title
    bare = title.split(":")[-1]
    return bare if bare in frames else None


def worst_case(entry, frames, edges, problems, names):
    memo, on_path = {}, set()

    def visit(node):
        if node in memo:
            return memo[node]
        if node in on_path:
            problems.append(f"recursion through {names.get(node, node)}")
            return 0, [node]
        on_path.add(node)
        deepest, chain = 0, []
        for callee in sorted(edges.get(node, ())):
            target = resolve(callee, frames)
            if target is None:
                bare = callee.split(":")[-1]
                if bare.startswith("__indirect_call") or "indirect" in bare:
                    problems.append(f"indirect call in {names.get(node, node)}")
                    continue
                depth, sub = kLibraryLeafBytes, [callee]
            else:
                depth, sub = visit(target)
            if depth > deepest:
                deepest, chain = depth, sub
        on_path.discard(node)
        memo[node] = (frames.get(node, 0) + deepest, [node] + chain)
        return memo[node]

    return visit(entry)


def short(label):
    """'gabarit::Status gabarit::track_step(const TableView&, ...)' -> 'gabarit::track_step'"""
    return label.split("(")[0].split()[-1]


def map_sections(map_path):
    sizes, symbols = {}, {}
    text = pathlib.Path(map_path).read_text()
    for name, addr, size in re.findall(r"^(\.[\w.]+)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)", text, re.M):
        sizes.setdefault(name, (int(addr, 16), int(size, 16)))
    for addr, sym in re.findall(r"^\s+0x([0-9a-f]+)\s+(gabarit_\w+)$", text, re.M):
        symbols[sym] = int(addr, 16)
    return sizes, symbols


def self_test():
    """The checks must be able to fail: a recursive pair and a dynamic frame."""
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        pathlib.Path(d, "a.ci").write_text(
            'graph: { title: "a.cpp"\n'
            'node: { title: "f" label: "void f()\\na.cpp:1:1\\n16 bytes (static)" }\n'
            'node: { title: "g" label: "void g()\\na.cpp:2:1\\n24 bytes (dynamic)" }\n'
            'edge: { sourcename: "f" targetname: "g" label: "a.cpp:1:9" }\n'
            'edge: { sourcename: "g" targetname: "f" label: "a.cpp:2:9" }\n}\n')
        frames, names, edges, kinds = load_graph(d)
        problems = [f"{kinds[t]} frame in {names[t]}" for t in frames if kinds[t] != "static"]
        depth, _ = worst_case("f", frames, edges, problems, names)
    ok = depth == 40 and any("recursion" in p for p in problems) and any("dynamic" in p for p in problems)
    print("self-test:", "PASS" if ok else f"FAIL (depth {depth}, problems {problems})")
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build")
    ap.add_argument("--map")
    ap.add_argument("--self-test", action="store_true", help="check that recursion and dynamic frames are caught")
    ap.add_argument("--flash-budget", type=int, default=2 * 1024 * 1024)
    ap.add_argument("--ram-budget", type=int, default=512 * 1024)
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    if not args.build or not args.map:
        ap.error("--build and --map are required")

    sizes, symbols = map_sections(args.map)
    size = lambda s: sizes.get(s, (0, 0))[1]
    stack_budget = size(".stack")
    frames, names, edges, kinds = load_graph(args.build)
    if not frames:
        print(f"FAIL: no call-graph files (*.ci) under {args.build}: build with -fcallgraph-info=su")
        return 1
    problems = [f"{kinds[t]} frame in {names[t]}" for t in frames if kinds[t] != "static"]

    # Entry points: the reset handler, and every global kernel/vector function.
    entries = [t for t in frames if t == "Reset_Handler"]
    entries += sorted(t for t in frames if ":" not in t and t.startswith("_ZN7gabarit") and "mcu" not in t)
    print("## Worst-case stack (bytes, from -fcallgraph-info=su)\n")
    print("| entry point | worst case | deepest chain |")
    print("|---|---:|---|")
    firmware_worst = 0
    for entry in entries:
        depth, chain = worst_case(entry, frames, edges, problems, names)
        if entry == "Reset_Handler":
            firmware_worst = depth
        shown = " → ".join(short(names.get(c, c.split(":")[-1])) for c in chain)
        print(f"| `{short(names[entry])}` | {depth} | {shown} |")
    need = firmware_worst + kExceptionFrameBytes
    print(f"\nFirmware: {firmware_worst} B worst case + {kExceptionFrameBytes} B exception frame = {need} B "
          f"of the {stack_budget} B stack reserved in firmware.ld")
    flash = sum(size(s) for s in (".isr_vector", ".text", ".rodata", ".ARM.exidx", ".init_array", ".data"))
    ram = sum(size(s) for s in (".data", ".bss", ".stack"))
    table = symbols.get("gabarit_table_end", 0) - symbols.get("gabarit_table", 0)
    vectors = symbols.get("gabarit_vectors_end", 0) - symbols.get("gabarit_vectors", 0)
    session = symbols.get("gabarit_session_end", 0) - symbols.get("gabarit_session", 0)
    print("\n## Memory (from the linker map)\n")
    print("| region | used | budget | share |")
    print("|---|---:|---:|---:|")
    print(f"| flash | {flash} | {args.flash_budget} | {100.0 * flash / args.flash_budget:.1f}% |")
    print(f"| RAM | {ram} | {args.ram_budget} | {100.0 * ram / args.ram_budget:.1f}% |")
    print(f"\nflash: code {size('.text')} B, table {table} B, test vectors {vectors} B, session vectors {session} B; "
          f"RAM: static buffers (.bss) {size('.bss')} B, stack {size('.stack')} B")

    if need > stack_budget:
        problems.append(f"stack: {need} B needed, {stack_budget} B reserved")
    if flash > args.flash_budget:
        problems.append(f"flash: {flash} B used, budget {args.flash_budget} B")
    if ram > args.ram_budget:
        problems.append(f"RAM: {ram} B used, budget {args.ram_budget} B")
    for p in sorted(set(problems)):
        print(f"FAIL: {p}")
    print("PASS: stack bounded, no recursion, within budget" if not problems else "")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
