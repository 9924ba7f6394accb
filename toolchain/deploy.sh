#!/usr/bin/env bash
# Installs the cross-built firmware on the robot's Raspberry Pi and (re)starts it with systemd.
#
#   toolchain/deploy.sh <user@pi-host> [--arch aarch64|armhf] [--build-dir DIR]
#                       [--install-deps] [--no-restart] [--dry-run]
#
# Copies, in one ssh connection (a tar stream), to the Pi:
#   <build-dir>/firmware/sen3bot   -> /opt/sen3bot/bin/sen3bot          (replaced atomically)
#   <build-dir>/firmware/sen3bot-*.so -> /opt/sen3bot/bin/ (the camera and vision rows' modules)
#   config/*.yaml                  -> /etc/sen3bot/  (a changed file's old copy: *.yaml.previous)
#   toolchain/sen3bot.service      -> /etc/systemd/system/sen3bot.service
# then, on the Pi as root (through sudo unless logging in as root): systemctl daemon-reload,
# enable and restart sen3bot.service, and shows its status.
#
#   --arch          aarch64 (64-bit Raspberry Pi OS, default) or armhf (32-bit)
#   --build-dir     where the cross build is (default <repo>/build-<arch>)
#   --install-deps  first apt-get install on the Pi the runtime libraries the binary needs:
#                   its and its modules' DT_NEEDED entries mapped to Debian packages through the sysroot's index
#                   (toolchain/sysroot.sh), e.g. libyaml-cpp0.7 libopencv-core406
#   --no-restart    install the files and the unit, but do not enable/restart the service
#   --dry-run       print every command instead of running it
#
# SEN3BOT_SSH_OPTS adds ssh options (e.g. "-p 2222 -i ~/.ssh/robot"). Needs on this machine:
# ssh, tar, readelf (binutils); on the Pi: tar, systemd, sudo (unless root).
set -euo pipefail

readonly script_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
readonly repo_dir="$(cd "${script_dir}/.." && pwd)"

usage() { sed -n '2,24p' "$0" | sed 's/^# \{0,1\}//'; }

target=""
arch=aarch64
build_dir=""
install_deps=0
restart=1
dry_run=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --arch) arch="$2"; shift ;;
    --build-dir) build_dir="$2"; shift ;;
    --install-deps) install_deps=1 ;;
    --no-restart) restart=0 ;;
    --dry-run) dry_run=1 ;;
    -h|--help) usage; exit 0 ;;
    -*) echo "deploy.sh: unknown option '$1'" >&2; exit 2 ;;
    *)
      if [[ -n "${target}" ]]; then echo "deploy.sh: one target only" >&2; exit 2; fi
      target="$1" ;;
  esac
  shift
done
if [[ -z "${target}" ]]; then
  usage >&2
  exit 2
fi
case "${arch}" in
  aarch64|arm64) arch=aarch64; elf_machine="AArch64" ;;
  armhf|arm) arch=armhf; elf_machine="ARM" ;;
  *) echo "deploy.sh: --arch must be aarch64 or armhf" >&2; exit 2 ;;
esac
build_dir="${build_dir:-${repo_dir}/build-${arch}}"
binary="${build_dir}/firmware/sen3bot"
sysroot="${SEN3BOT_SYSROOT:-${repo_dir}/.sysroot-${arch}}"
read -r -a ssh_opts <<< "${SEN3BOT_SSH_OPTS:-}"

readonly remote_bin_dir=/opt/sen3bot/bin
readonly remote_config_dir=/etc/sen3bot
readonly remote_unit=/etc/systemd/system/sen3bot.service

# Prints a command line, single-quoting the words that need it.
show() {
  local word sep=""
  for word in "$@"; do
    if [[ "${word}" =~ ^[A-Za-z0-9_./@:=+,|-]+$ ]]; then
      printf '%s%s' "${sep}" "${word}"
    else
      printf "%s'%s'" "${sep}" "${word//\'/\'\\\'\'}"
    fi
    sep=" "
  done
  printf '\n'
}

# --- Check the binary ---------------------------------------------------------------------------
if [[ ! -f "${binary}" ]]; then
  if [[ "${dry_run}" == 0 ]]; then
    echo "deploy.sh: ${binary} not found; build it first: toolchain/cross-test.sh ${arch}" >&2
    exit 1
  fi
  echo "# (dry run) ${binary} does not exist yet"
elif ! readelf -h "${binary}" | grep -q "Machine:.*${elf_machine}"; then
  echo "deploy.sh: ${binary} is not an ${arch} executable:" >&2
  readelf -h "${binary}" | grep Machine >&2
  exit 1
fi

# The rows whose libraries are heavy, loaded when the configuration uses them (firmware/row_module.hpp).
mapfile -t modules < <(find "${build_dir}/firmware" -maxdepth 1 -name 'sen3bot-*.so' 2>/dev/null | sort)

# --- Runtime packages for --install-deps ---------------------------------------------------------
runtime_packages=()
if [[ "${install_deps}" == 1 ]]; then
  soname_index="${sysroot}/.sen3bot-sysroot.sonames"
  if [[ -f "${binary}" && -f "${soname_index}" ]]; then
    mapfile -t needed < <(for f in "${binary}" "${modules[@]}"; do readelf -d "$f"; done |
                            sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | sort -u)
    for soname in "${needed[@]}"; do
      pkg="$(awk -v so="${soname}" '$1 == so { print $2; exit }' "${soname_index}")"
      if [[ -z "${pkg}" ]]; then
        echo "deploy.sh: no package in the sysroot provides ${soname}" >&2
        exit 1
      fi
      runtime_packages+=("${pkg}")
    done
    mapfile -t runtime_packages < <(printf '%s\n' "${runtime_packages[@]}" | sort -u)
  else
    # Without a binary or sysroot index: what the firmware links today (docs/cross-build.md).
    runtime_packages=(libc6 libgcc-s1 libstdc++6 libyaml-cpp0.7)
    echo "# no binary/sysroot index: installing the documented default runtime packages"
  fi
fi

# --- Stage the files and the installer script ----------------------------------------------------
stage="$(mktemp -d "${TMPDIR:-/tmp}/sen3bot-deploy.XXXXXX")"
trap 'rm -rf "${stage}"' EXIT
mkdir -p "${stage}/bin" "${stage}/config"
if [[ -f "${binary}" ]]; then cp "${binary}" "${stage}/bin/sen3bot"; fi
for module in "${modules[@]}"; do cp "${module}" "${stage}/bin/"; done
cp "${repo_dir}"/config/*.yaml "${stage}/config/"
cp "${script_dir}/sen3bot.service" "${stage}/sen3bot.service"

# Runs on the Pi, as root, from the unpacked staging directory.
{
  echo 'set -eu'
  echo 'cd "$(dirname "$0")"'
  if [[ "${#runtime_packages[@]}" -gt 0 ]]; then
    echo 'export DEBIAN_FRONTEND=noninteractive'
    echo 'apt-get update -q'
    printf 'apt-get install -y -q --no-install-recommends'
    printf ' %q' "${runtime_packages[@]}"
    echo
  fi
  cat <<EOF
install -d -m 0755 ${remote_bin_dir} ${remote_config_dir}
# A new inode, then rename: replaces the binary even while the old one runs.
install -m 0755 bin/sen3bot ${remote_bin_dir}/.sen3bot.new
mv -f ${remote_bin_dir}/.sen3bot.new ${remote_bin_dir}/sen3bot
for m in bin/sen3bot-*.so; do
  [ -f "\$m" ] || continue
  install -m 0644 "\$m" ${remote_bin_dir}/.module.new
  mv -f ${remote_bin_dir}/.module.new ${remote_bin_dir}/\$(basename "\$m")
done
for f in config/*.yaml; do
  dest=${remote_config_dir}/\$(basename "\$f")
  if [ -f "\$dest" ] && ! cmp -s "\$f" "\$dest"; then cp -p "\$dest" "\$dest.previous"; fi
  install -m 0644 "\$f" "\$dest"
done
install -m 0644 sen3bot.service ${remote_unit}
systemctl daemon-reload
EOF
  if [[ "${restart}" == 1 ]]; then
    cat <<EOF
systemctl enable sen3bot.service
systemctl restart sen3bot.service
sleep 1
systemctl --no-pager --lines=15 status sen3bot.service || true
EOF
  fi
} > "${stage}/install.sh"

# --- Copy and run -------------------------------------------------------------------------------
tty_opt=()
if [[ -t 0 ]]; then tty_opt=(-t); fi   # lets sudo on the Pi ask for a password
unpack_cmd='d=$(mktemp -d /tmp/sen3bot-deploy.XXXXXX) && tar -C "$d" -xzf - && echo "$d"'
install_cmd() {  # <remote staging dir>
  echo "if [ \"\$(id -u)\" = 0 ]; then sh $1/install.sh; else sudo sh $1/install.sh; fi;" \
       "rc=\$?; rm -rf $1; exit \$rc"
}

echo "deploy: ${binary} + ${#modules[@]} row modules + config/*.yaml + sen3bot.service -> ${target}"
if [[ "${#runtime_packages[@]}" -gt 0 ]]; then
  echo "deploy: runtime packages for the Pi: ${runtime_packages[*]}"
fi
if [[ "${dry_run}" == 1 ]]; then
  echo "# 1. copy: a tar stream of the staged files into a fresh directory on the Pi"
  show tar -C "${stage}" -czf - . \| ssh "${ssh_opts[@]}" "${target}" "${unpack_cmd}"
  echo "# 2. install (as root) and restart; REMOTE_DIR is the directory printed by step 1"
  show ssh "${tty_opt[@]}" "${ssh_opts[@]}" "${target}" "$(install_cmd REMOTE_DIR)"
  echo "# REMOTE_DIR/install.sh:"
  sed 's/^/#   /' "${stage}/install.sh"
  exit 0
fi

remote_dir="$(tar -C "${stage}" -czf - . | ssh "${ssh_opts[@]}" "${target}" "${unpack_cmd}")"
if [[ "${remote_dir}" != /tmp/sen3bot-deploy.* ]]; then
  echo "deploy.sh: copying to ${target} failed" >&2
  exit 1
fi
ssh "${tty_opt[@]}" "${ssh_opts[@]}" "${target}" "$(install_cmd "${remote_dir}")"
echo "deploy: done"
