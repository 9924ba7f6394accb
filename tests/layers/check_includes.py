#!/usr/bin/env python3
"""The layers of docs/firmware.md, checked on the sources: every file of a layer includes
project headers only from its own layer or the layers before it. Layers that share a rank
(the applications over navigation: ssc, cobot, formation, view) may not include each other.

usage: check_includes.py SOURCE_DIR | --self-test
Prints each violation (file, line, the header and the layer that owns it); exit status 1 when
there is one. --self-test runs the check on a small tree with seeded violations and fails
unless it finds exactly those.
"""
import os
import re
import sys
import tempfile

# The order of docs/firmware.md ("Layers"): a folder's rank, and the folders it may include.
RANKS = {
    "hal": 0,
    "lib": 1,
    "drivers": 2,
    "runtime": 3,
    "nav": 4,
    "ssc": 5, "cobot": 5, "slam": 5, "formation": 5, "view": 5,
    "firmware": 6,
    "centre": 7,
    "sim": 8,
}
# hal's error type is the one project header the neutral libraries use.
ALLOWED = {("lib", "sen3bot/hal/result.hpp")}
SOURCES = (".cpp", ".hpp", ".h", ".cc")
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def layer_of(path):
    top = path.split(os.sep, 1)[0]
    return top if top in RANKS else None


def header_owners(root):
    """Each header as it is included (its path under an include/ folder) -> its layers."""
    owners = {}
    for layer in RANKS:
        for dirpath, _, files in os.walk(os.path.join(root, layer)):
            rel_dir = os.path.relpath(dirpath, root)
            parts = rel_dir.split(os.sep)
            if "include" not in parts:
                continue
            base = os.path.join(root, *parts[: parts.index("include") + 1])
            for name in files:
                owners.setdefault(os.path.relpath(os.path.join(dirpath, name), base), set()).add(layer)
    # The composition layers' headers sit beside their sources and are included by name.
    for layer in ("firmware", "centre"):
        folder = os.path.join(root, layer)
        if os.path.isdir(folder):
            for name in os.listdir(folder):
                if name.endswith(".hpp"):
                    owners.setdefault(name, set()).add(layer)
    return owners


def check_file(root, rel, owners, out):
    layer = layer_of(rel)
    bad = 0
    with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE.match(line)
            if not m or (layer, m.group(1)) in ALLOWED:
                continue
            if os.path.exists(os.path.join(root, os.path.dirname(rel), m.group(1))):
                continue  # a header beside the file
            for owner in sorted(owners.get(m.group(1), ())):
                if owner == layer or RANKS[owner] < RANKS[layer]:
                    continue
                out.append(f"{rel}:{number}: {layer}/ includes {m.group(1)} of {owner}/")
                bad += 1
    return bad


def check_tree(root):
    owners = header_owners(root)
    files = []
    for layer in RANKS:
        for dirpath, _, names in os.walk(os.path.join(root, layer)):
            files += [os.path.relpath(os.path.join(dirpath, n), root) for n in names if n.endswith(SOURCES)]
    out = []
    for rel in sorted(files):
        check_file(root, rel, owners, out)
    return len(files), out


def self_test():
    """A tree with one include of each kind; only the seeded violations may be reported."""
    tree = {
        "hal/include/sen3bot/hal/result.hpp": "",
        "hal/src/clock.cpp": '#include "sen3bot/hal/result.hpp"\n',
        "lib/json/include/sen3bot/json/json.hpp": '#include "sen3bot/hal/result.hpp"\n',
        "drivers/p2os/src/codec.cpp": '#include "sen3bot/json/json.hpp"\n#include "sen3bot/msg/people.hpp"\n',
        "runtime/include/sen3bot/msg/people.hpp": '#include "sen3bot/hal/result.hpp"\n',
        "view/include/sen3bot/view/view.hpp": "",
        "ssc/src/centre.cpp": '#include "sen3bot/view/view.hpp"\n',
        "firmware/cli_util.hpp": "",
        "firmware/cli_util.cpp": '#include "cli_util.hpp"\n',
        "runtime/src/bus.cpp": '#include "cli_util.hpp"\n',
        "firmware/cmd_sgp.cpp": '#include "sen3bot/sim/report/figure.hpp"\n#include "sen3bot/msg/people.hpp"\n',
        "sim/report/include/sen3bot/sim/report/figure.hpp": '#include "sen3bot/msg/people.hpp"\n',
    }
    expected = {
        "drivers/p2os/src/codec.cpp:2: drivers/ includes sen3bot/msg/people.hpp of runtime/",
        "ssc/src/centre.cpp:1: ssc/ includes sen3bot/view/view.hpp of view/",
        "firmware/cmd_sgp.cpp:1: firmware/ includes sen3bot/sim/report/figure.hpp of sim/",
        "runtime/src/bus.cpp:1: runtime/ includes cli_util.hpp of firmware/",
    }
    with tempfile.TemporaryDirectory() as root:
        for rel, text in tree.items():
            os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        _, out = check_tree(root)
    for line in out:
        print(line)
    if set(out) != expected or len(out) != len(expected):
        print("self-test: expected exactly:\n  " + "\n  ".join(sorted(expected)))
        return 1
    print("self-test: the seeded violations, and only they, were found")
    return 0


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    if argv[1] == "--self-test":
        return self_test()
    checked, out = check_tree(argv[1])
    for line in out:
        print(line)
    print(f"{checked} files, {len(out)} includes across the layers")
    return 1 if out else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
