#!/usr/bin/env python3
"""Worst-case stack and memory use of the Cortex-M firmware.

Usage: firmware_report.py --build DIR --map FIRMWARE.map [--flash-budget BYTES] [--ram-budget BYTES]
       firmware_report.py --build DIR --stack-only     (the stack checks alone, any objects' call graphs)
       firmware_report.py --self-test

Stack: reads the call graphs GCC writes with -fcallgraph-info=su (one .ci
file per object under DIR, less the other firmware images' objects), joins them across files and computes, for the
firmware entry (Reset_Handler) and every kernel entry point, the deepest
chain of frames. Fails on recursion (a cycle), on a frame GCC marks dynamic
or bounded (alloca/VLA), on an indirect call, and when the firmware's worst
case plus the exception allowance exceeds the stack reserved in firmware.ld
(the map's .stack section).
Library leaves (memcpy, memset, memcmp: newlib's are leaf functions using no
stack beyond pushed registers) count as kLibraryLeafBytes; any other callee
with no call graph fails the check (its stack, and any cycle through it,
would be unknown). A lambda is shown as its enclosing function followed by
`::<lambda at FILE:LINE>`, so a chain through the lambdas of one function
does not read as recursion.

Memory: flash and RAM used, from the linker map's output sections, and the
share of flash taken by the embedded table, test vectors, session vectors and
particle vectors.
Exit status 0 when everything is within budget, 1 otherwise.
"""
import argparse
import pathlib
import re
import sys

kLibraryLeafBytes = 32      # pushed registers of a newlib string routine
kLibraryLeaves = {"memcpy", "memset", "memmove", "memcmp", "strlen", "__builtin_memcpy", "__builtin_memset",
                  "__builtin_memmove", "__builtin_memcmp", "__aeabi_memcpy", "__aeabi_memset", "__aeabi_memclr",
                  "__aeabi_memcpy4", "__aeabi_memclr4", "__aeabi_memset4", "__aeabi_memmove"}
kExceptionFrameBytes = 104  # a fault taken at the deepest point: FP context frame (26 words)

NODE = re.compile(r'node: \{ title: "([^"]+)" label: "([^"]*)"')
EDGE = re.compile(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"')
FRAME = re.compile(r'\\n(\d+) bytes \((static|dynamic|dynamic,bounded)\)')


def other_image(ci, image):
    """Whether a call-graph file belongs to another firmware image than
    `image` (the objects under CMakeFiles/IMAGE.dir): each image defines its
    own app_main, and joined they would be one node with one image's frame."""
    if image is None:
        return False
    dirs = [part[:-4] for part in ci.parts if part.endswith(".dir")]
    return any(d.startswith("gabarit-firmware") and d != image for d in dirs)


def load_graph(build_dir, image=None):
    frames, names, edges, kinds = {}, {}, {}, {}
    for ci in sorted(pathlib.Path(build_dir).rglob("*.ci")):
        if other_image(ci, image):
            continue
        text = ci.read_text()
        for title, label in NODE.findall(text):
            m = FRAME.search(label)
            lines = label.split("\\n")
            names.setdefault(title, lines[0])
            if m:  # a definition (declarations have no frame)
                frames[title] = int(m.group(1))
                kinds[title] = m.group(2)
                names[title] = display_name(lines[0], lines[1] if len(lines) > 2 else "")
        for src, dst in EDGE.findall(text):
            edges.setdefault(src, set()).add(dst)
    return frames, names, edges, kinds


def resolve(title, frames):
    """A call to an external symbol names it without the defining file's
    prefix. A call to a complete-object constructor or destructor (C1/D1)
    reaches the base-object one (C2/D2) that GCC defines and aliases it to."""
    if title in frames:
        return title
    bare = title.split(":")[-1]
    if bare in frames:
        return bare
    for complete, base in (("C1E", "C2E"), ("D1E", "D2E")):
        if complete in bare:
            for candidate in (title.replace(complete, base), bare.replace(complete, base)):
                if candidate in frames:
                    return candidate
    return None


def library_leaf(name):
    """newlib's string routines and libgcc's arithmetic helpers (__aeabi_*):
    leaves, or chains of a few pushed registers (at most 8 B in the firmware's
    disassembly), within kLibraryLeafBytes."""
    return name in kLibraryLeaves or re.fullmatch(r"__aeabi_\w+", name) is not None


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
                if not library_leaf(bare):
                    problems.append(f"no call graph for {names.get(callee, bare)} (called from {names.get(node, node)})")
                depth, sub = kLibraryLeafBytes, [callee]
            else:
                depth, sub = visit(target)
            if depth > deepest:
                deepest, chain = depth, sub
        on_path.discard(node)
        memo[node] = (frames.get(node, 0) + deepest, [node] + chain)
        return memo[node]

    return visit(entry)


def display_name(signature, location):
    """A definition's name as the report shows it: a lambda keeps the enclosing
    function's name and gains '::<lambda at FILE:LINE>' (GCC labels it
    'f(args)::<lambda(args)>'), so that distinct functions never share a name."""
    if "::<lambda" not in signature:
        return signature
    where = ":".join(pathlib.Path(location).name.split(":")[:2]) if location else "?"
    return signature.split("::<lambda")[0] + f"::<lambda at {where}>"


def short(label):
    """'gabarit::Status gabarit::track_step(const TableView&, ...)' -> 'gabarit::track_step';
    'R f(args)::<lambda at x.cpp:12>' -> 'f::<lambda at x.cpp:12>'"""
    lam = ""
    if "::<lambda at " in label:
        label, lam = label.split("::<lambda at ", 1)
        lam = "::<lambda at " + lam
    depth, cut = 0, len(label)
    for i, ch in enumerate(label):  # the name ends at the parameter list's '(' (not one inside a template)
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth -= 1
        elif ch == "(" and depth == 0:
            cut = i
            break
    return label[:cut].split()[-1] + lam


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


def stack_only(build_dir):
    frames, names, edges, kinds = load_graph(build_dir)
    if not frames:
        print(f"FAIL: no call-graph files (*.ci) under {build_dir}: build with -fcallgraph-info=su")
        return 1
    problems = [f"{kinds[t]} frame in {names[t]}" for t in frames if kinds[t] != "static"]
    for entry in sorted(t for t in frames if ":" not in t):
        depth, chain = worst_case(entry, frames, edges, problems, names)
        shown = " → ".join(short(names.get(c, c.split(":")[-1])) for c in chain)
        print(f"{short(names[entry])}: {depth} B: {shown}")
    for p in sorted(set(problems)):
        print(f"FAIL: {p}")
    print("PASS: stack bounded, no recursion" if not problems else "")
    return 1 if problems else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build")
    ap.add_argument("--map")
    ap.add_argument("--self-test", action="store_true", help="check that recursion and dynamic frames are caught")
    ap.add_argument("--stack-only", action="store_true",
                    help="the stack checks alone, every global function of the call graphs an entry point (no map)")
    ap.add_argument("--flash-budget", type=int, default=2 * 1024 * 1024)
    ap.add_argument("--ram-budget", type=int, default=512 * 1024)
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    if args.stack_only:
        if not args.build:
            ap.error("--stack-only needs --build")
        return stack_only(args.build)
    if not args.build or not args.map:
        ap.error("--build and --map are required")

    sizes, symbols = map_sections(args.map)
    size = lambda s: sizes.get(s, (0, 0))[1]
    stack_budget = size(".stack")
    # The image's own objects (its map is IMAGE.map) and the libraries'.
    frames, names, edges, kinds = load_graph(args.build, pathlib.Path(args.map).stem)
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
    particle = symbols.get("gabarit_particle_end", 0) - symbols.get("gabarit_particle", 0)
    print("\n## Memory (from the linker map)\n")
    print("| region | used | budget | share |")
    print("|---|---:|---:|---:|")
    print(f"| flash | {flash} | {args.flash_budget} | {100.0 * flash / args.flash_budget:.1f}% |")
    print(f"| RAM | {ram} | {args.ram_budget} | {100.0 * ram / args.ram_budget:.1f}% |")
    print(f"\nflash: code {size('.text')} B, table {table} B, test vectors {vectors} B, session vectors {session} B, "
          f"particle vectors {particle} B; "
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
