#!/usr/bin/env python3
"""docs/architecture.md quotes the firmware's own account of its data flow: each block between
    <!-- generated: sen3bot ARGS... -->
and
    <!-- end generated -->
is a fenced code block holding what `sen3bot ARGS...` prints, run from the source folder.

    check_architecture.py SEN3BOT ROOT           fails, naming the block, when one differs
    check_architecture.py SEN3BOT ROOT --write   rewrites the blocks from the binary
    check_architecture.py --self-test            the check catches a changed line
"""
import os
import re
import shlex
import subprocess
import sys
import tempfile

BLOCK = re.compile(r"(<!-- generated: sen3bot (?P<args>[^>]*?) -->\n```(?P<lang>\w*)\n)(?P<body>.*?)(```\n<!-- end generated -->)",
                   re.S)


def run(binary, root, args):
    done = subprocess.run([binary] + shlex.split(args), cwd=root, capture_output=True, text=True, timeout=60)
    if done.returncode != 0:
        raise SystemExit(f"sen3bot {args}: exit status {done.returncode}: {done.stderr.strip()}")
    return done.stdout


def check(binary, root, doc, write):
    text = open(doc, encoding="utf-8").read()
    blocks = list(BLOCK.finditer(text))
    if not blocks:
        print(f"{doc}: no generated block")
        return 1
    stale = []

    def replace(m):
        now = run(binary, root, m.group("args"))
        if now != m.group("body"):
            stale.append(m.group("args"))
        return m.group(1) + now + m.group(5)

    new_text = BLOCK.sub(replace, text)
    if write:
        if new_text != text:
            open(doc, "w", encoding="utf-8").write(new_text)
        print(f"{doc}: {len(blocks)} blocks, {len(stale)} rewritten")
        return 0
    for args in stale:
        print(f"{doc}: the block of `sen3bot {args}` is not what the firmware prints now; "
              f"rewrite it with: python3 tests/layers/check_architecture.py build/firmware/sen3bot . --write")
    if not stale:
        print(f"{doc}: {len(blocks)} generated blocks current")
    return 1 if stale else 0


def self_test():
    with tempfile.TemporaryDirectory() as tmp:
        fake = os.path.join(tmp, "sen3bot")
        with open(fake, "w") as f:
            f.write("#!/bin/sh\necho \"flow of $*\"\necho line two\n")
        os.chmod(fake, 0o755)
        doc = os.path.join(tmp, "architecture.md")
        block = "<!-- generated: sen3bot graph --config a.yaml -->\n```text\n{}```\n<!-- end generated -->\n"
        with open(doc, "w") as f:
            f.write("# title\n\n" + block.format("flow of graph --config a.yaml\nline two\n") + "\nmore\n")
        if check(fake, tmp, doc, False) != 0:
            print("self-test: a current block was reported stale")
            return 1
        with open(doc, "w") as f:
            f.write("# title\n\n" + block.format("flow of graph --config a.yaml\nline 2\n"))
        if check(fake, tmp, doc, False) == 0:
            print("self-test: a changed line was not caught")
            return 1
        check(fake, tmp, doc, True)
        if check(fake, tmp, doc, False) != 0:
            print("self-test: --write did not bring the block up to date")
            return 1
    print("self-test: passed")
    return 0


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(self_test())
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    binary, root = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    sys.exit(check(binary, root, os.path.join(root, "docs", "architecture.md"), "--write" in sys.argv[3:]))
