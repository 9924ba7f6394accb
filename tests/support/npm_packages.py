"""The npm packages of a test's package-lock.json, installed once into a build folder.

    from npm_packages import install_packages
    install_packages(HERE, cache, "vda-5050-lib", log)

`npm ci` runs only when the folder does not hold an install of the same package.json and
package-lock.json (their hash is kept in the folder) with `marker` (a package name) present;
an flock makes runs that share the folder install once. Install scripts are not run.
"""
import fcntl
import hashlib
import os
import shutil
import subprocess
import time
from pathlib import Path


def install_packages(source: Path, cache: Path, marker: str, log, env=None):
    cache.mkdir(parents=True, exist_ok=True)
    digest = hashlib.sha256()
    for name in ("package.json", "package-lock.json"):
        digest.update((source / name).read_bytes())
    key = digest.hexdigest()
    stamp = cache / "installed.sha256"
    with open(cache / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if (stamp.exists() and stamp.read_text().strip() == key
                and (cache / "node_modules" / marker / "package.json").exists()):
            log(f"npm packages up to date in {cache}")
            return
        for name in ("package.json", "package-lock.json"):
            shutil.copyfile(source / name, cache / name)
        stamp.unlink(missing_ok=True)
        log(f"npm ci in {cache}")
        started = time.monotonic()
        result = subprocess.run(
            ["npm", "ci", "--ignore-scripts", "--no-audit", "--no-fund", "--loglevel=error"],
            cwd=cache, env=dict(os.environ, **(env or {})), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True)
        if result.returncode != 0:
            raise RuntimeError(f"npm ci failed (exit {result.returncode}):\n{result.stdout}")
        stamp.write_text(key + "\n")
        log(f"npm ci took {time.monotonic() - started:.1f} s")


SKIP = 77


def prepare(source: Path, cache: Path, marker: str, log, env=None, missing=()):
    """Node.js, npm and the packages: None when ready, SKIP (77) when node, npm or anything in
    `missing` is absent, 1 when the install failed."""
    node, npm = shutil.which("node"), shutil.which("npm")
    absent = [n for n, p in (("node", node), ("npm", npm)) if p is None] + list(missing)
    if absent:
        log(f"skipped: {', '.join(absent)} not installed (toolchain/bootstrap.sh)")
        return SKIP
    version = subprocess.run([node, "--version"], capture_output=True, text=True).stdout.strip()
    log(f"node {version} ({node})")
    try:
        install_packages(source, cache, marker, log, env)
    except (RuntimeError, OSError) as error:
        log(str(error))
        return 1
    return None


def stop_process(process, name, log, grace=5.0):
    """SIGTERM, then SIGKILL after `grace` seconds."""
    if process is None or process.poll() is not None:
        return
    process.terminate()
    try:
        process.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        log(f"{name} ignored SIGTERM for {grace} s: killing it")
        process.kill()
        process.wait()
