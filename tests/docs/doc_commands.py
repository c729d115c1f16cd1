#!/usr/bin/env python3
"""Every command README.md and docs/*.md tell a reader to run, run.

Each ```sh fence of each document is read in order; a line ending in a
backslash continues on the next; comments and blank lines are dropped. Every
command is then either

  - run here, in one empty folder per document, in the document's order, with
    `g=build/release/tools/gabarit` (and any `build/release/tools/gabarit`)
    pointed at the gabarit under test; it must exit 0 and every file it names
    with -o/--out/--stats/--plots/--report must exist afterwards; or
  - run elsewhere, by a named test or target listed in ELSEWHERE below (the
    firmware path, CI's presets, the virtual board); a pattern that no
    longer matches any command fails, so the list stays true; or
  - long (minutes to an hour), listed in LONG: run only with --long, which
    the `docs-commands-long` target does (outside CI).

A command that is in no list is run, so a new command in the docs is tested
by default.

Usage: doc_commands.py SOURCE_DIR GABARIT [--long] [--only DOC]
       doc_commands.py --self-test
"""
import os
import re
import shlex
import subprocess
import sys
import tempfile

DOCS = ["README.md", "docs/*.md"]

# Commands another test or target runs, and which.
ELSEWHERE = [
    (r"^tools/scripts/test-all\.sh$", "CI itself (.ci/run runs it)"),
    (r"^tools/scripts/demo\.sh\b", "docs.demo (tests/docs/demo_test.sh)"),
    (r"^cmake --preset cortex-m7 && cmake --build build/cortex-m7\b", "docs.firmware_path_on_a_clean_tree (cortex-m7 preset)"),
    (r"^cmake --install build/cortex-m7 --prefix", "docs.firmware_path_on_a_clean_tree (cortex-m7 preset)"),
    (r"^cmake --workflow --preset release && cmake --workflow --preset aarch64\b", "CI's release and aarch64 presets (tools/scripts/test-all.sh)"),
    (r"hil run --dut virtual-board --sequence seq --report report --faults cycle:6:", "hil.virtual_board (aarch64 preset, tests/hil/virtual_board_hil.sh)"),
    (r"hil run --dut virtual-board --sequence seq --report soak --soak 50\b", "the hil-soak-virtual-board target (about 90 minutes)"),
    (r"hil lava-job --sequence seq --firmware build/cortex-m7/", "hil.lava.mps2-an500 (cortex-m7 preset, tests/hil/lava_run_test.sh)"),
    (r"^apt-get install --no-install-recommends lava-dispatcher python3-jinja2$", "CI's setup (tools/scripts/setup-debian.sh)"),
    (r"^printf \"\{%% extends 'gabarit-qemu-", "hil.lava.mps2-an500 (cortex-m7 preset, tests/hil/lava_run_test.sh)"),
    (r"^python3 hil/lava/render_device\.py ", "hil.lava.mps2-an500 (cortex-m7 preset, tests/hil/lava_run_test.sh)"),
    (r"^lava-run --job-id ", "hil.lava.mps2-an500 (cortex-m7 preset, tests/hil/lava_run_test.sh)"),
]

# Commands that take minutes: run by the docs-commands-long target only.
LONG = [
    (r"\bbench --out bench-out$", "the full benchmark, a few minutes"),
    (r"\bbench --decimation --out bench-decimation$", "the decimation study, about 25 minutes"),
]

OUTPUT_FLAGS = ("-o", "--out", "--stats", "--plots", "--report")


def fences(text):
    """The commands of every ```sh fence, continuation lines joined."""
    commands, inside, pending = [], False, ""
    for line in text.splitlines():
        if not inside:
            inside = re.match(r"^```(sh|bash|shell)\s*$", line) is not None
            continue
        if line.startswith("```"):
            inside = False
            continue
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1].rstrip() + " "
            continue
        line, pending = (pending + line.strip()).strip(), ""
        if line and not line.startswith("#"):
            commands.append(line)
    return commands


def without_comment(command):
    """The command without a trailing `# ...` comment (outside quotes)."""
    # Cut at the first '#' that starts a word outside quotes.
    quote = None
    for i, c in enumerate(command):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (i == 0 or command[i - 1].isspace()):
            return command[:i].rstrip()
    return command.rstrip()


def classify(command):
    bare = without_comment(command)
    for pattern, where in ELSEWHERE:
        if re.search(pattern, bare):
            return "elsewhere", where, pattern
    for pattern, why in LONG:
        if re.search(pattern, bare):
            return "long", why, pattern
    return "run", "", None


def outputs(command):
    words = shlex.split(without_comment(command).replace("$g", "g"), posix=True)
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in OUTPUT_FLAGS]


def documents(source):
    import glob
    found = []
    for pattern in DOCS:
        found += sorted(glob.glob(os.path.join(source, pattern)))
    return found


def run_document(path, commands, gabarit, long_too):
    failures, ran = [], 0
    with tempfile.TemporaryDirectory() as work:
        for command in commands:
            kind, why, _ = classify(command)
            if kind == "elsewhere" or (kind == "long" and not long_too):
                print(f"  ({'elsewhere: ' + why if kind == 'elsewhere' else 'long, --long only: ' + why}) {command}")
                continue
            line = without_comment(command)
            if line == "g=build/release/tools/gabarit":
                continue
            line = line.replace("build/release/tools/gabarit", gabarit)
            print(f"  + {line}", flush=True)
            env = dict(os.environ, g=gabarit)
            result = subprocess.run(["bash", "-euo", "pipefail", "-c", line], cwd=work, env=env,
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            ran += 1
            if result.returncode != 0:
                print("\n".join(result.stdout.splitlines()[-20:]))
                failures.append(f"{os.path.basename(path)}: exit {result.returncode}: {command}")
                break  # the later commands read what this one writes
            for out in outputs(line):
                if not os.path.exists(os.path.join(work, out)):
                    failures.append(f"{os.path.basename(path)}: '{command}' did not write {out}")
    return ran, failures


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    args = [a for a in argv[1:] if not a.startswith("--")]
    long_too = "--long" in argv
    only = argv[argv.index("--only") + 1] if "--only" in argv else None
    if only:
        args.remove(only)
    if len(args) != 2:
        print(__doc__)
        return 2
    source, gabarit = os.path.abspath(args[0]), os.path.abspath(args[1])
    failures, total, used = [], 0, set()
    for path in documents(source):
        rel = os.path.relpath(path, source)
        if only and rel != only:
            continue
        commands = fences(open(path, encoding="utf-8").read())
        if not commands:
            continue
        print(f"{rel}: {len(commands)} commands")
        for command in commands:
            used.add(classify(command)[2])
        ran, failed = run_document(path, commands, gabarit, long_too)
        total += ran
        failures += failed
    if not only:
        for pattern, _ in ELSEWHERE + LONG:
            if pattern not in used:
                failures.append(f"the list names a command no document has any more: {pattern}")
    for failure in failures:
        print(f"FAIL: {failure}")
    if failures:
        return 1
    print(f"PASS: {total} commands from the docs ran")
    return 0


def self_test():
    text = "x\n```sh\n# c\na \\\n  b  # note\n\n$g x -o 'p q' --out r\n```\n```text\nno\n```\n"
    commands = fences(text)
    assert commands == ["a b  # note", "$g x -o 'p q' --out r"], commands
    assert without_comment(commands[0]) == "a b"
    assert without_comment("echo '#x' # y") == "echo '#x'"
    assert outputs(commands[1]) == ["p q", "r"], outputs(commands[1])
    assert classify("tools/scripts/test-all.sh")[0] == "elsewhere"
    assert classify("build/release/tools/gabarit bench --out bench-out  # minutes")[0] == "long"
    assert classify("$g synth -o seq")[0] == "run"
    with tempfile.TemporaryDirectory() as work:
        doc = os.path.join(work, "d.md")
        ran, failed = run_document(doc, ["true", "false", "touch never"], "/bin/true", False)
        assert ran == 2 and len(failed) == 1, (ran, failed)
        ran, failed = run_document(doc, ["true -o missing"], "/bin/true", False)
        assert failed and "did not write" in failed[0], failed
    print("PASS: doc_commands self-test")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
