#!/usr/bin/env python3
"""The simulated robot against an independent VDA 5050 master control (vda-5050-lib, npm).

  run_master_peer.py --sim BUILD/firmware/sen3bot-sim --cache BUILD/tests/peers/vda5050-npm
                     [--source-dir REPO] [--timeout S] [--keep]
  run_master_peer.py --self-check --cache BUILD/tests/peers/vda5050-npm

--self-check: instead of the robot, a retained connection and a state that breaks the 2.0
schema are published for a made-up vehicle, and the master must fail on the validation:
the proof that a message of the robot's failing validation fails the test.

1. Installs the npm packages of package-lock.json into the cache folder with `npm ci`, unless
   the folder already holds an install of the same package.json and lock file (their hash).
2. Starts Mosquitto on a free loopback port: plain, anonymous, its configuration in a
   temporary folder.
3. Writes the firmware configuration from config/sim.yaml: navigation.goals and tasks.mission
   removed, tasks.fleet added, a fleet section for that broker (serial number r1, VDA 5050
   2.0.0, map lab), the map paths made absolute.
4. Runs `sen3bot-sim run --clock realtime` on it in the background and `node master.mjs`.
5. Stops both and the broker; exits 0 when the master reported success, 1 when it or the
   set-up failed, 77 (skipped) when node, npm or mosquitto are not installed.
"""
import argparse
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "support"))
import npm_packages  # noqa: E402  (tests/support)
SERIAL = "r1"


def log(message):
    print(f"run_master_peer: {message}", file=sys.stderr, flush=True)


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def port_accepts(port):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(0.5)
        return s.connect_ex(("127.0.0.1", port)) == 0


def fleet_config(source: Path, broker_port: int) -> str:
    """config/sim.yaml as a fleet robot: the text transformed line by line, so that every other
    setting stays the one the repository ships."""
    config_dir = source.parent
    out = []
    section = None      # the top-level key the line is in
    skip_indent = None  # dropping a block nested deeper than this
    for line in source.read_text().splitlines():
        stripped = line.lstrip(" ")
        indent = len(line) - len(stripped)
        if skip_indent is not None:
            if stripped == "" or stripped.startswith("#") or indent > skip_indent:
                continue
            skip_indent = None
        top = re.match(r"^([A-Za-z_]\w*):", line)
        if top:
            section = top.group(1)
        key = re.match(r"^\s+([A-Za-z_]\w*):", line)
        if section == "navigation" and key and key.group(1) == "goals":
            continue  # the fleet's orders give the goals
        if section == "tasks" and key and key.group(1) == "mission":
            skip_indent = indent  # the mission task and its settings
            continue
        # Paths are relative to the configuration file: made absolute for the copy elsewhere.
        path = re.match(r"^(\s+(?:map|waypoints):\s+)([^\s#{}\[\]]+)(.*)$", line)
        if path and not path.group(2).startswith("/"):
            line = f"{path.group(1)}{(config_dir / path.group(2)).resolve()}{path.group(3)}"
        out.append(line)
        if top and section == "tasks":
            out.append("  fleet:")
            out.append("    arena_bytes: 4MiB")
    if not any(re.match(r"^tasks:", l) for l in out):
        raise RuntimeError(f"{source}: no tasks section")
    out += [
        "",
        "# The robot as a VDA 5050 vehicle of the peer test's master control.",
        "fleet:",
        f"  broker: mqtt://127.0.0.1:{broker_port}",
        f"  serial_number: {SERIAL}",
        "  version: 2.0.0",
        "  map_id: lab",
        "",
    ]
    return "\n".join(out)


def mqtt_publish_retained(port, messages):
    """Publishes (topic, text) pairs retained at QoS 0: a bare MQTT 3.1.1 client."""
    def length(n):
        out = bytearray()
        while True:
            n, digit = divmod(n, 128)
            out.append(digit | (0x80 if n else 0))
            if not n:
                return bytes(out)

    def text(value):
        data = value.encode()
        return len(data).to_bytes(2, "big") + data

    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        body = text("MQTT") + bytes([4, 0x02]) + (30).to_bytes(2, "big") + text("sen3bot-peer-self-check")
        s.sendall(b"\x10" + length(len(body)) + body)
        ack = s.recv(4)
        if len(ack) != 4 or ack[0] != 0x20 or ack[3] != 0:
            raise RuntimeError(f"the broker refused the connection: {ack!r}")
        for topic, payload in messages:
            body = text(topic) + payload.encode()
            s.sendall(b"\x31" + length(len(body)) + body)
        s.sendall(b"\xe0\x00")


def self_check(node, cache, port, timeout):
    serial = "validation-check"
    header = (f'"headerId":{{id}},"timestamp":"2026-12-03T10:00:00.00Z","version":"2.0.0",'
              f'"manufacturer":"Sen3Bot","serialNumber":"{serial}"')
    prefix = f"uagv/v2/Sen3Bot/{serial}/"
    state = ('{' + header.format(id=1) + ',"orderId":"","orderUpdateId":0,"lastNodeId":"","lastNodeSequenceId":0,'
             '"nodeStates":[],"edgeStates":[],"driving":false,"actionStates":[],'
             '"batteryState":{"batteryCharge":50,"charging":false},"operatingMode":"FULLY_AUTOMATIC",'
             '"errors":[],"safetyState":{"eStop":"NONE","fieldViolation":false},'
             '"agvPosition":{"x":2.5,"y":2.0,"theta":0,"mapId":"lab","positionInitialized":true}}')
    mqtt_publish_retained(port, [
        (prefix + "connection", '{' + header.format(id=0) + ',"connectionState":"ONLINE"}'),
        (prefix + "state", state),
    ])
    result = subprocess.run([node, str(HERE / "master.mjs"), "--broker", f"mqtt://127.0.0.1:{port}",
                             "--serial", serial, "--modules", str(cache), "--timeout", str(timeout)],
                            capture_output=True, text=True)
    sys.stderr.write(result.stderr)
    expected = "fails the library's VDA 5050 2.0.0 validation"
    if result.returncode == 1 and expected in result.stderr and "operatingMode" in result.stderr:
        log("self-check: the master failed on the invalid state, as it must")
        return 0
    log(f"self-check: the master did not fail on the invalid state (exit {result.returncode}):\n{result.stdout}")
    return 1


def stop(process, name, grace=5.0):
    npm_packages.stop_process(process, name, log, grace)


def tail(path: Path, lines=60):
    try:
        text = path.read_text(errors="replace").splitlines()
    except OSError:
        return ""
    return "\n".join(text[-lines:])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sim", help="the sen3bot-sim binary")
    parser.add_argument("--self-check", action="store_true",
                        help="check that a state failing validation fails the master (no robot)")
    parser.add_argument("--cache", required=True, help="the folder the npm packages are installed in")
    parser.add_argument("--source-dir", default=str(HERE.parents[2]), help="the repository (config/sim.yaml)")
    parser.add_argument("--timeout", type=float, default=240.0, help="the master's time limit, s")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder (config, logs)")
    args = parser.parse_args()
    if not args.sim and not args.self_check:
        parser.error("--sim is required (or --self-check)")

    mosquitto = shutil.which("mosquitto")
    if mosquitto is None and Path("/usr/sbin/mosquitto").exists():
        mosquitto = "/usr/sbin/mosquitto"
    ready = npm_packages.prepare(HERE, Path(args.cache).resolve(), "vda-5050-lib", log,
                                 missing=[] if mosquitto else ["mosquitto"])
    if ready is not None:
        return ready
    node = shutil.which("node")

    work = Path(tempfile.mkdtemp(prefix="sen3bot-vda5050-peer-"))
    broker = sim = master = None
    rc = 1
    try:
        port = free_port()
        (work / "mosquitto.conf").write_text(
            f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\nlog_dest stderr\n")
        broker_log = open(work / "mosquitto.log", "w")
        broker = subprocess.Popen([mosquitto, "-c", str(work / "mosquitto.conf")],
                                  stdout=broker_log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 10
        while not port_accepts(port):
            if broker.poll() is not None or time.monotonic() > deadline:
                log(f"mosquitto did not listen on port {port}:\n{tail(work / 'mosquitto.log')}")
                return 1
            time.sleep(0.05)
        log(f"mosquitto on 127.0.0.1:{port}")
        if args.self_check:
            rc = self_check(node, Path(args.cache).resolve(), port, min(args.timeout, 20.0))
            return rc

        config = work / "fleet.yaml"
        config.write_text(fleet_config(Path(args.source_dir) / "config" / "sim.yaml", port))
        # The robot outlives the master's time limit a little; it is stopped when the master ends.
        duration = int(args.timeout) + 30
        sim_log = open(work / "sim.log", "w")
        sim = subprocess.Popen([args.sim, "run", "--config", str(config), "--clock", "realtime",
                                "--duration", str(duration)],
                               stdout=sim_log, stderr=subprocess.STDOUT)
        log(f"sen3bot-sim pid {sim.pid}, its output in {work / 'sim.log'}")

        started = time.monotonic()
        master = subprocess.Popen([node, str(HERE / "master.mjs"), "--broker", f"mqtt://127.0.0.1:{port}",
                                   "--serial", SERIAL, "--modules", str(Path(args.cache).resolve()),
                                   "--timeout", str(args.timeout)],
                                  stdout=subprocess.PIPE, text=True)
        while master.poll() is None:
            if sim.poll() is not None:
                log(f"sen3bot-sim ended (exit {sim.returncode}) before the master:\n{tail(work / 'sim.log')}")
                stop(master, "node")
                return 1
            time.sleep(0.1)
        output = master.stdout.read()
        sys.stdout.write(output)
        sys.stdout.flush()
        log(f"master exit {master.returncode} after {time.monotonic() - started:.1f} s")
        if master.returncode != 0:
            log(f"sen3bot-sim output (last lines):\n{tail(work / 'sim.log')}")
            return 1
        rc = 0
    finally:
        stop(master, "node")
        stop(sim, "sen3bot-sim", grace=10.0)
        stop(broker, "mosquitto")
        if args.keep or rc != 0:
            log(f"kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)
    return rc


if __name__ == "__main__":
    sys.exit(main())
