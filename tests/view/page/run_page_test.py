#!/usr/bin/env python3
"""The robot's built-in live view page in headless Chromium, against the simulated robot.

  run_page_test.py --sim BUILD/firmware/sen3bot-sim --cache BUILD/tests/view/page-npm
                   [--source-dir REPO] [--out DIR] [--scenario thesis-sgp] [--timeout S] [--keep]
  run_page_test.py --url http://127.0.0.1:PORT/ --report DIR/report.json --cache DIR [--out DIR]

1. Installs the npm packages of package-lock.json (playwright-core, which downloads no
   browser) into the cache folder with `npm ci`, unless the folder already holds an install of
   the same package.json and lock file (their hash).
2. Runs, in the repository (its config/sim.yaml), `sen3bot-sim sim --scenario thesis-sgp --view --view-port 0 --view-hold 120 --report
   OUT/run` (lockstep), reads the port from its `view: http://127.0.0.1:PORT/ ...` line and
   waits for OUT/run/report.json, written before the hold.
3. Runs `node page_check.mjs` on the page: Debian's Chromium (/usr/bin/chromium), a desktop
   and a phone viewport; the screenshots go to OUT/run/page.png and OUT/run/page-phone.png.
4. Stops the simulator. Exits 0 when the check passed, 1 when it or the set-up failed, 77
   (skipped) when node, npm or Chromium are not installed.

With --url and --report the check runs against a server that is already up (no simulator).
"""
import argparse
import os
import queue
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "support"))
import npm_packages  # noqa: E402  (tests/support)
SKIP = npm_packages.SKIP
CHROMIUM = "/usr/bin/chromium"
VIEW_LINE = re.compile(r"view: (http://[^\s/]+:(\d+)/)")


def log(message):
    print(f"run_page_test: {message}", file=sys.stderr, flush=True)


def stop(process, name, grace=5.0):
    npm_packages.stop_process(process, name, log, grace)


def tail(path: Path, lines=40):
    try:
        return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return ""


def start_simulator(args, run_dir: Path, sim_log: Path):
    """Starts the lockstep run with the view; returns (process, url) once report.json exists."""
    command = [str(Path(args.sim).resolve()), "sim", "--scenario", args.scenario, "--view", "--view-port", "0",
               "--view-hold", str(args.hold), "--report", str(run_dir)]
    log(" ".join(command))
    sim = subprocess.Popen(command, cwd=args.source_dir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           text=True, bufsize=1)
    lines = queue.Queue()

    def pump():  # the simulator's output into its log, the view line into the queue
        with open(sim_log, "w") as out:
            for line in sim.stdout:
                out.write(line)
                out.flush()
                if VIEW_LINE.search(line):
                    lines.put(line)

    threading.Thread(target=pump, daemon=True).start()
    deadline = time.monotonic() + args.timeout
    url = None
    while url is None:
        try:
            match = VIEW_LINE.search(lines.get(timeout=0.2))
            url = match.group(1)
        except queue.Empty:
            if sim.poll() is not None:
                raise RuntimeError(f"sen3bot-sim ended (exit {sim.returncode}) without a 'view:' line:\n{tail(sim_log)}")
            if time.monotonic() > deadline:
                raise RuntimeError(f"no 'view: http://...' line within {args.timeout} s:\n{tail(sim_log)}")
    log(f"view at {url}")
    report = run_dir / "report.json"
    while not report.exists():
        if sim.poll() is not None:
            raise RuntimeError(f"sen3bot-sim ended (exit {sim.returncode}) before writing {report}:\n{tail(sim_log)}")
        if time.monotonic() > deadline:
            raise RuntimeError(f"no {report} within {args.timeout} s:\n{tail(sim_log)}")
        time.sleep(0.1)
    time.sleep(0.2)  # the file is complete once the hold starts; a moment for the last write
    return sim, url


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sim", help="the sen3bot-sim binary")
    parser.add_argument("--url", help="check a view server that is already up (with --report)")
    parser.add_argument("--report", help="its report.json (with --url)")
    parser.add_argument("--cache", required=True, help="the folder the npm packages are installed in")
    parser.add_argument("--out", help="where the run's report and the screenshots go (default: a temporary folder)")
    parser.add_argument("--source-dir", default=str(HERE.parents[2]),
                        help="the repository; the simulator runs there (config/sim.yaml)")
    parser.add_argument("--scenario", default="thesis-sgp", help="the simulated scenario")
    parser.add_argument("--hold", type=int, default=120, help="the simulator's --view-hold, s")
    parser.add_argument("--timeout", type=float, default=120.0, help="time limit of the run and of the page's data, s")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = parser.parse_args()
    if not args.sim and not (args.url and args.report):
        parser.error("--sim is required (or --url with --report)")

    missing = [] if os.access(CHROMIUM, os.X_OK) else [f"chromium ({CHROMIUM})"]
    cache = Path(args.cache).resolve()
    ready = npm_packages.prepare(HERE, cache, "playwright-core", log, {"PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD": "1"}, missing)
    if ready is not None:
        return ready
    node = shutil.which("node")

    temporary = args.out is None
    out = Path(tempfile.mkdtemp(prefix="sen3bot-view-page-")) if temporary else Path(args.out).resolve()
    if not temporary and out.exists():
        shutil.rmtree(out)
    run_dir = out / "run"
    run_dir.mkdir(parents=True, exist_ok=True)
    sim = None
    rc = 1
    try:
        if args.sim:
            try:
                sim, url = start_simulator(args, run_dir, out / "sim.log")
            except RuntimeError as error:
                log(str(error))
                return 1
            report = run_dir / "report.json"
        else:
            url, report = args.url, Path(args.report).resolve()
        check = subprocess.run(
            [node, str(HERE / "page_check.mjs"), "--url", url, "--report", str(report),
             "--screenshot", str(run_dir / "page.png"), "--modules", str(cache), "--chromium", CHROMIUM,
             "--timeout", str(min(args.timeout, 60.0))],
            stdout=subprocess.PIPE, text=True, timeout=args.timeout + 120)
        sys.stdout.write(check.stdout)
        sys.stdout.flush()
        if sim is not None and sim.poll() is not None:
            log(f"sen3bot-sim ended (exit {sim.returncode}) during the check, before its hold ran out")
            rc = 1
        elif check.returncode == SKIP:
            rc = SKIP
        else:
            rc = 0 if check.returncode == 0 else 1
        log(f"page check exit {check.returncode}; screenshots in {run_dir}")
        if rc == 1 and sim is not None:
            log(f"sen3bot-sim output (last lines):\n{tail(out / 'sim.log')}")
    except subprocess.TimeoutExpired:
        log("page_check.mjs did not finish in time")
        rc = 1
    finally:
        stop(sim, "sen3bot-sim", grace=10.0)
        if temporary and not args.keep and rc == 0:
            shutil.rmtree(out, ignore_errors=True)
        else:
            log(f"kept {out}")
    return rc


if __name__ == "__main__":
    sys.exit(main())
