#!/usr/bin/env python3
"""The simulator's live view against the official Foxglove WebSocket client (npm).

  run_view_peer.py --sim BUILD/firmware/sen3bot-sim --cache BUILD/tests/view/view-npm
                   [--source-dir REPO] [--scenario NAME] [--duration S] [--keep]

1. Installs the npm packages of package-lock.json (@foxglove/ws-protocol, ws,
   @foxglove/schemas, ajv, ajv-formats) into the cache folder with `npm ci`, unless the folder
   already holds an install of the same package.json and lock file (their hash).
2. Starts `sen3bot-sim sim --scenario thesis-sgp --view --view-port 0 --realtime --report TMP`
   in the repository (its config/sim.yaml) and reads the port from the line it prints,
   `view: http://127.0.0.1:PORT/ ...`.
3. Runs `node conformance.mjs` against ws://127.0.0.1:PORT/ with the configuration's map.
4. Stops the simulator (SIGINT, SIGKILL after a timeout); exits 0 when the client's checks
   passed, 1 when they or the set-up failed, 77 (skipped) when node or npm is not installed.
"""
import argparse
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "support"))
import npm_packages  # noqa: E402  (tests/support)
VIEW_LINE = re.compile(r"^view: http://([^/\s]+):(\d+)/")


def log(message):
    print(f"run_view_peer: {message}", file=sys.stderr, flush=True)


class Simulator:
    """sen3bot-sim with its output copied to a log file by a thread (so a full pipe never
    blocks it); `port` is set once the view line was printed."""

    def __init__(self, argv, cwd, log_path: Path):
        self.log_path = log_path
        self.port = None
        self.listening = threading.Event()
        self.process = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        stdin=subprocess.DEVNULL)
        self.thread = threading.Thread(target=self._drain, daemon=True)
        self.thread.start()

    def _drain(self):
        with open(self.log_path, "wb") as out:
            for raw in self.process.stdout:
                out.write(raw)
                out.flush()
                match = VIEW_LINE.match(raw.decode(errors="replace"))
                if match and self.port is None:
                    self.port = int(match.group(2))
                    self.listening.set()
        self.listening.set()  # the simulator ended: nobody waits for a line that cannot come

    def wait_listening(self, timeout):
        self.listening.wait(timeout)
        return self.port

    def running(self):
        return self.process.poll() is None

    def stop(self, grace=10.0):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                log(f"sen3bot-sim ignored SIGINT for {grace} s: killing it")
                self.process.kill()
                self.process.wait()
        self.thread.join(timeout=5)
        return self.process.returncode

    def tail(self, lines=40):
        try:
            text = self.log_path.read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return "\n".join(text[-lines:])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sim", required=True, help="the sen3bot-sim binary")
    parser.add_argument("--cache", required=True, help="the folder the npm packages are installed in")
    parser.add_argument("--source-dir", default=str(HERE.parents[2]), help="the repository (config/sim.yaml)")
    parser.add_argument("--scenario", default="thesis-sgp")
    parser.add_argument("--duration", type=float, default=20.0, help="the client's least time subscribed, s")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder (report, log)")
    args = parser.parse_args()

    cache = Path(args.cache).resolve()
    ready = npm_packages.prepare(HERE, cache, "@foxglove/ws-protocol", log)
    if ready is not None:
        return ready
    node = shutil.which("node")

    source = Path(args.source_dir).resolve()
    work = Path(tempfile.mkdtemp(prefix="sen3bot-view-peer-"))
    sim = None
    rc = 1
    try:
        sim_argv = [str(Path(args.sim).resolve()), "sim", "--scenario", args.scenario, "--view", "--view-port", "0",
                    "--realtime", "--report", str(work / "report")]
        log(" ".join(sim_argv))
        sim = Simulator(sim_argv, cwd=source, log_path=work / "sim.log")
        port = sim.wait_listening(30.0)
        if port is None:
            log(f"sen3bot-sim printed no 'view: http://...' line within 30 s "
                f"({'running' if sim.running() else f'exit {sim.process.returncode}'}):\n{sim.tail()}")
            return 1
        url = f"ws://127.0.0.1:{port}/"
        log(f"sen3bot-sim pid {sim.process.pid} serves {url}; its output in {work / 'sim.log'}")

        client_argv = [node, str(HERE / "conformance.mjs"), "--url", url, "--modules", str(cache),
                       "--map", str(source / "config" / "maps" / "lab.yaml"),
                       "--duration", str(args.duration), "--timeout", str(args.duration + 60)]
        started = time.monotonic()
        client = subprocess.run(client_argv, timeout=args.duration + 90)
        log(f"conformance.mjs exit {client.returncode} after {time.monotonic() - started:.1f} s")
        if not sim.running():
            log(f"sen3bot-sim ended (exit {sim.process.returncode}) while the client ran")
        rc = 0 if client.returncode == 0 else 1
        if rc != 0:
            log(f"sen3bot-sim output (last lines):\n{sim.tail()}")
    except subprocess.TimeoutExpired:
        log("conformance.mjs did not end in time")
        rc = 1
    finally:
        if sim is not None:
            code = sim.stop()
            log(f"sen3bot-sim stopped (exit {code})")
        if args.keep or rc != 0:
            log(f"kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)
    return rc


if __name__ == "__main__":
    sys.exit(main())
