#!/usr/bin/env python3
"""The robot binary holds no simulator, emulator, simulated-worker, scene-renderer or fleet
centre code: its defined symbols (nm -C) are checked against those namespaces and classes.
The figure library is allowed: `sen3bot sgp --png` draws.

usage: check_symbols.py NM BINARY [--expect-violations]
Prints each forbidden symbol found (the first few of each kind); exit status 1 when there is
one. With --expect-violations the meaning is turned round (a binary that must be caught, the
simulator's, proves the check can fail): exit status 1 when none is found.
"""
import re
import subprocess
import sys

FORBIDDEN = [
    ("the simulator", re.compile(r"\bsen3bot::sim::")),
    ("the P2OS emulator", re.compile(r"\bsen3bot::p2os::(P2osEmulator|EmulatorRunner|PtyEmulatorRunner|EmulatorWorld)\b")),
    ("the LMS200 emulator", re.compile(r"\bsen3bot::lms200::(Lms200Emulator|Lms200PtyRunner|WallWorld|SimulatedLine)\b")),
    ("the CANopen node emulator", re.compile(r"\bsen3bot::canopen::IoNodeEmulator\b")),
    ("the simulated workers", re.compile(r"\bsen3bot::cobot::WorkerSimulator\b")),
    ("the tag scene renderer", re.compile(r"\bsen3bot::cobot::TagSceneRenderer\b")),
    ("the fleet centre's service", re.compile(r"\bsen3bot::ssc::Service\b")),
    ("the formation service", re.compile(r"\bsen3bot::formation::FormationService\b")),
]
SHOWN = 3


def main(argv):
    if len(argv) not in (3, 4) or (len(argv) == 4 and argv[3] != "--expect-violations"):
        print(__doc__, file=sys.stderr)
        return 2
    nm, binary = argv[1], argv[2]
    expect = len(argv) == 4
    listing = subprocess.run([nm, "-C", "--defined-only", binary], check=True, capture_output=True, text=True).stdout
    symbols = [line.split(" ", 2)[-1] for line in listing.splitlines() if line.count(" ") >= 2]
    found = 0
    for what, pattern in FORBIDDEN:
        hits = [s for s in symbols if pattern.search(s)]
        if hits:
            found += len(hits)
            print(f"{binary}: {len(hits)} symbols of {what}, e.g.")
            for s in hits[:SHOWN]:
                print(f"  {s}")
    print(f"{len(symbols)} defined symbols, {found} forbidden in the robot binary")
    if len(symbols) == 0:
        print("no symbols read: the check cannot judge this binary")
        return 1
    return (0 if found else 1) if expect else (1 if found else 0)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
