#!/usr/bin/env bash
# Builds a Debian bookworm sysroot for cross-building Sen3Bot for the Raspberry Pi.
#
#   toolchain/sysroot.sh [aarch64|armhf] [--force] [--print-dir]
#
# The sysroot is a plain directory of unpacked Debian arm64 (or armhf) packages: the libraries
# the firmware and its tests link against (yaml-cpp, GoogleTest/GoogleMock, Google Benchmark,
# OpenCV core/imgproc/imgcodecs/objdetect/ml) and their whole dependency closure, including libc6 and
# its dynamic loader so qemu-user can run the test binaries (qemu -L <sysroot>).
#
# Why a separate directory and not `dpkg --add-architecture arm64; apt install foo:arm64`:
# multi-arch installs must have exactly the same version as the host's copy of every shared
# package, so they upgrade (or refuse to install) host packages and leave foreign packages in
# the host's dpkg database. Here apt runs with a private state (own package lists, an EMPTY
# dpkg status file, own archive cache) and only downloads; each .deb is unpacked with
# `dpkg-deb -x`. The host's dpkg database and packages are never touched, and no root is needed.
#
# The mirrors are the host's own: the bookworm stanzas of /etc/apt/sources.list(.d) are copied
# (Architectures fields dropped). Set SEN3BOT_SYSROOT_SOURCES to a deb822 .sources file to use
# other mirrors. The host's apt.conf.d is still read, so proxies and Acquire settings apply.
#
# Environment:
#   SEN3BOT_SYSROOT            sysroot directory   (default <repo>/.sysroot-<arch>)
#   SEN3BOT_SYSROOT_APT        private apt state and .deb cache (default <sysroot>.apt); keep
#                              it (e.g. as a CI cache) to make a rebuild skip the download
#   SEN3BOT_SYSROOT_IMGCODECS  0 to leave out libopencv-imgcodecs-dev and its GDAL closure
#                              (default 1; see docs/cross-build.md)
#   SEN3BOT_SYSROOT_SOURCES    deb822 sources file to use instead of the host's
#
# Re-running is quick: a stamp file in the sysroot records a hash of the package list, the
# architecture, the sources and this script; when it matches, nothing is done.
set -euo pipefail

# --- Packages unpacked into the sysroot (their dependency closure is added by apt). ---------
# Add what new code links against here; runtime packages (lib*<soversion>) for the Pi are listed
# in docs/cross-build.md.
SYSROOT_PACKAGES=(
  libc6 libstdc++6 libgcc-s1   # the target's loader + libc pair that runs the tests under qemu
  libyaml-cpp-dev
  libgtest-dev libgmock-dev
  libbenchmark-dev
  libeigen3-dev zlib1g-dev     # map building: sparse Cholesky, gzipped logs
  libopencv-core-dev libopencv-imgproc-dev
  libjpeg62-turbo-dev libpng-dev  # JPEG in, PNG out (OpenCV's imgcodecs only for the tests)
  libopencv-objdetect406       # the on-board people detector (HOG); its -dev package below
  libssl-dev                   # camera: libcrypto (Digest auth)
  libavcodec-dev libavutil-dev libswscale-dev  # camera: H.264 decoding
  libpugixml-dev libcurl4-openssl-dev          # camera: ONVIF
  libmosquitto-dev             # fleet: MQTT
  libwebsockets-dev            # view: the live view's server
  libopencv-ml-dev             # operation recognition (cv::ml)
)
# Unpacked without their dependencies: libopencv-objdetect-dev (the header and the .so link)
# depends on libopencv-highgui-dev, which would bring Qt 5, Mesa and GTK (~150 packages) for
# headers the detector never includes.
SYSROOT_NO_DEPS_PACKAGES=(libopencv-objdetect-dev)
# libopencv-imgcodecs-dev links libgdal32: +~100 packages, +~50 MiB download, +~200 MB unpacked.
SYSROOT_IMGCODECS_PACKAGES=(libopencv-imgcodecs-dev)
# Marked as already installed in the private status file, so apt does not pull them in. They
# are never linked against nor loaded by the tests: libglx-mesa0 is the GLX vendor library that
# libglvnd (libGLX.so.0, a dependency of libopencv_core) dlopen()s only when an OpenGL context is
# created; it alone drags in Mesa's DRI drivers and LLVM (~40 packages, ~45 MiB, ~200 MB).
SYSROOT_ASSUME_INSTALLED=(libglx-mesa0)
# ----------------------------------------------------------------------------------------------

readonly script_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
readonly repo_dir="$(cd "${script_dir}/.." && pwd)"

arch=aarch64
force=0
print_dir=0
for arg in "$@"; do
  case "${arg}" in
    aarch64|arm64) arch=aarch64 ;;
    armhf|arm) arch=armhf ;;
    --force) force=1 ;;
    --print-dir) print_dir=1 ;;
    -h|--help) sed -n '2,31p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "sysroot.sh: unknown argument '${arg}'" >&2; exit 2 ;;
  esac
done

case "${arch}" in
  aarch64) deb_arch=arm64 ;;
  armhf) deb_arch=armhf ;;
esac

sysroot="${SEN3BOT_SYSROOT:-${repo_dir}/.sysroot-${arch}}"
apt_dir="${SEN3BOT_SYSROOT_APT:-${sysroot%/}.apt}"
if [[ "${print_dir}" == 1 ]]; then
  echo "${sysroot}"
  exit 0
fi

packages=("${SYSROOT_PACKAGES[@]}")
if [[ "${SEN3BOT_SYSROOT_IMGCODECS:-1}" == 1 ]]; then
  packages+=("${SYSROOT_IMGCODECS_PACKAGES[@]}")
fi

log() { echo "[sysroot ${arch}] $*" >&2; }

# Emits the bookworm 'deb' stanzas of the host's apt sources as deb822, without Architectures.
host_sources() {
  local f
  for f in /etc/apt/sources.list.d/*.sources; do
    [[ -f "${f}" ]] || continue
    awk 'BEGIN { RS = ""; ORS = "\n\n" }
      {
        out = ""; keep_type = 0; keep_suite = 0; enabled = 1
        n = split($0, lines, "\n")
        for (i = 1; i <= n; i++) {
          line = lines[i]
          if (line ~ /^[ \t]*#/) continue
          if (line ~ /^Architectures:/) continue
          if (line ~ /^Types:/) { if (line ~ /[ \t]deb([ \t]|$)/) keep_type = 1; line = "Types: deb" }
          if (line ~ /^Suites:/ && line ~ /bookworm/) keep_suite = 1
          if (line ~ /^Enabled:[ \t]*no/) enabled = 0
          out = out line "\n"
        }
        if (keep_type && keep_suite && enabled) printf "%s\n", out
      }' "${f}"
  done
  # One-line format: "deb [options] uri suite components...".
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
    [[ -f "${f}" ]] || continue
    awk '$1 == "deb" && /bookworm/ {
        opts = ""; i = 2
        if ($2 ~ /^\[/) {
          while (i <= NF) { opts = opts " " $i; if ($i ~ /\]$/) { i++; break } i++ }
        }
        uri = $i; suite = $(i + 1); comps = ""
        for (j = i + 2; j <= NF; j++) comps = comps " " $j
        printf "Types: deb\nURIs: %s\nSuites: %s\nComponents:%s\n", uri, suite, comps
        if (match(opts, /signed-by=[^ \]]+/))
          printf "Signed-By: %s\n", substr(opts, RSTART + 10, RLENGTH - 10)
        printf "\n"
      }' "${f}"
  done
}

if [[ -n "${SEN3BOT_SYSROOT_SOURCES:-}" ]]; then
  sources="$(cat "${SEN3BOT_SYSROOT_SOURCES}")"
else
  sources="$(host_sources)"
fi
if [[ -z "${sources//[[:space:]]/}" ]]; then
  log "no Debian bookworm 'deb' source found in /etc/apt/sources.list(.d);" \
      "set SEN3BOT_SYSROOT_SOURCES to a deb822 .sources file"
  exit 1
fi

case "$(realpath -m "${sysroot}")" in
  /|/usr|/usr/*|/lib*|/etc|/etc/*|"${HOME:-/root}") log "refusing sysroot directory '${sysroot}'"; exit 2 ;;
esac
if [[ -d "${sysroot}" && -n "$(ls -A "${sysroot}")" && ! -f "${sysroot}/.sen3bot-sysroot.packages" ]]; then
  log "'${sysroot}' exists and is not a sysroot made by this script; refusing to replace it"
  exit 2
fi

stamp_file="${sysroot}/.sen3bot-sysroot.stamp"
stamp="$( { echo "${deb_arch}"; printf '%s\n' "${packages[@]}" "${SYSROOT_ASSUME_INSTALLED[@]}" \
              "${SYSROOT_NO_DEPS_PACKAGES[@]}"; \
            echo "${sources}"; \
            cat "${BASH_SOURCE[0]}"; } | sha256sum | cut -d' ' -f1)"
if [[ "${force}" == 0 && -f "${stamp_file}" && "$(cat "${stamp_file}")" == "${stamp}" ]]; then
  log "up to date: ${sysroot}"
  exit 0
fi

for tool in apt-get dpkg-deb sha256sum realpath; do
  command -v "${tool}" >/dev/null || { log "missing '${tool}' (run toolchain/bootstrap.sh --cross)"; exit 1; }
done

start_s=${SECONDS}
mkdir -p "${apt_dir}"/{lists/partial,archives/partial,sources.list.d,preferences.d,cache}
# A dpkg status file with nothing installed (but the placeholders): apt resolves the full
# dependency closure and, being download-only, installs nothing anywhere.
: > "${apt_dir}/status"
for placeholder in "${SYSROOT_ASSUME_INSTALLED[@]}"; do
  printf 'Package: %s\nStatus: install ok installed\nVersion: 0\nArchitecture: %s\n%s\n\n' \
    "${placeholder}" "${deb_arch}" "Description: placeholder (not unpacked into the sysroot)" \
    >> "${apt_dir}/status"
done
printf '%s\n' "${sources}" > "${apt_dir}/sources.list.d/sen3bot-sysroot.sources"
: > "${apt_dir}/sources.list"

# Command-line options override everything from the host's apt.conf(.d).
apt_opts=(
  -o "APT::Architecture=${deb_arch}"
  -o "APT::Architectures=${deb_arch}"
  -o "APT::Install-Recommends=false"
  -o "APT::Install-Suggests=false"
  -o "APT::Get::AllowUnauthenticated=false"
  -o "Dir::State=${apt_dir}"
  -o "Dir::State::Lists=${apt_dir}/lists"
  -o "Dir::State::status=${apt_dir}/status"
  -o "Dir::State::extended_states=${apt_dir}/extended_states"
  -o "Dir::Cache=${apt_dir}/cache"
  -o "Dir::Cache::archives=${apt_dir}/archives"
  -o "Dir::Cache::pkgcache=${apt_dir}/cache/pkgcache.bin"
  -o "Dir::Cache::srcpkgcache=${apt_dir}/cache/srcpkgcache.bin"
  -o "Dir::Etc::SourceList=${apt_dir}/sources.list"
  -o "Dir::Etc::SourceParts=${apt_dir}/sources.list.d"
  -o "Dir::Etc::Preferences=${apt_dir}/preferences"
  -o "Dir::Etc::PreferencesParts=${apt_dir}/preferences.d"
  -o "Dir::Log=${apt_dir}"
  -o "Debug::NoLocking=true"
  -o "Acquire::Languages=none"
  -o "Acquire::Retries=3"
  -o "Acquire::By-Hash=force"
  -o "Acquire::IndexTargets::deb::Contents-deb::DefaultEnabled=false"
)
apt_private() { apt-get -q "${apt_opts[@]}" "$@"; }

log "updating private ${deb_arch} package lists in ${apt_dir}"
# Mirrors are sometimes caught mid-sync ("File has unexpected size"): retry the update. If one
# index still fails (e.g. bookworm-security), carry on with the others, loudly: the sysroot then
# holds the point-release version of a few packages, which has the same ABI.
for attempt in 1 2 3; do
  if apt_private update >"${apt_dir}/update.log" 2>&1; then break; fi
  if [[ "${attempt}" == 3 ]]; then
    grep -E '^(E|W|Err):' "${apt_dir}/update.log" >&2 || cat "${apt_dir}/update.log" >&2
    if compgen -G "${apt_dir}/lists/*_Packages*" >/dev/null; then
      log "WARNING: some package indexes failed to download; using the ones that did" \
          "(re-run with --force later for a complete one)"
      break
    fi
    log "no package index could be downloaded"; exit 1
  fi
  log "apt-get update failed (attempt ${attempt}), retrying in $((attempt * 10)) s"
  sleep $((attempt * 10))
done

# Resolve the closure against the empty status, then map each "Inst" line to its .deb name.
log "resolving: ${packages[*]}"
mapfile -t debs < <(apt_private install -s -y "${packages[@]}" | awk '
  $1 == "Inst" {
    name = $2; version = $3; sub(/^\(/, "", version)
    # "Inst name (version origin [arch])", sometimes followed by "[]".
    if (!match($0, /\[[a-z0-9]+\]\)/)) { print "cannot parse: " $0 > "/dev/stderr"; exit 1 }
    arch = substr($0, RSTART + 1, RLENGTH - 3)
    gsub(/:/, "%3a", version)
    print name "_" version "_" arch ".deb"
  }')
if [[ "${#debs[@]}" == 0 ]]; then
  log "apt resolved no packages"; exit 1
fi
# --print-uris lists only what is not in the archive cache yet.
download_bytes="$(apt_private install --print-uris -qq -y "${packages[@]}" \
                    | awk '{ s += $3 } END { print s + 0 }')"
log "${#debs[@]} packages; to download: $((download_bytes / 1024 / 1024)) MiB"

dl_start_s=${SECONDS}
apt_private install --download-only -y "${packages[@]}" >/dev/null
# `apt-get download` fetches one .deb, no dependencies, into the current directory.
for name in "${SYSROOT_NO_DEPS_PACKAGES[@]}"; do
  (cd "${apt_dir}/archives" && apt_private download "${name}" >/dev/null)
  mapfile -t found < <(cd "${apt_dir}/archives" && ls -t "${name}"_*_"${deb_arch}".deb 2>/dev/null)
  if [[ "${#found[@]}" == 0 ]]; then
    log "apt-get download ${name} left no .deb in ${apt_dir}/archives"; exit 1
  fi
  debs+=("${found[0]}")
done
log "download took $((SECONDS - dl_start_s)) s"

# Unpack into a fresh directory so packages dropped from the list do not linger.
tmp_root="${sysroot%/}.new"
rm -rf "${tmp_root}"
mkdir -p "${tmp_root}"
for deb in "${debs[@]}"; do
  if [[ ! -f "${apt_dir}/archives/${deb}" ]]; then
    log "expected ${deb} in ${apt_dir}/archives"; exit 1
  fi
  # -X unpacks and lists; the list becomes "<shared library file name> <package>" for every
  # versioned lib*.so.* the package ships, with which toolchain/deploy.sh maps the binary's
  # DT_NEEDED entries to the packages the Pi needs.
  dpkg-deb -X "${apt_dir}/archives/${deb}" "${tmp_root}" \
    | awk -v pkg="${deb%%_*}" '{ sub(/^.*\//, "") } /^(lib|ld-).*\.so\.[0-9]/ { print $0, pkg }'
done > "${tmp_root}/.sen3bot-sysroot.sonames"
printf '%s\n' "${debs[@]}" > "${tmp_root}/.sen3bot-sysroot.packages"
deb_bytes="$(cd "${apt_dir}/archives" && du -cb "${debs[@]}" | tail -1 | cut -f1)"
log "unpacked ${#debs[@]} packages ($((deb_bytes / 1024 / 1024)) MiB of .deb files)"

# Documentation is not needed to build or run.
rm -rf "${tmp_root}"/usr/share/{doc,man,info,locale,lintian,bug}

# Maintainer scripts are not run, so do by hand what libblas3's and liblapack3's postinst do
# with update-alternatives: libblas.so.3/liblapack.so.3 (needed by libopencv_core) in the
# multiarch directory, pointing at the reference implementation.
case "${arch}" in
  aarch64) triplet=aarch64-linux-gnu ;;
  armhf) triplet=arm-linux-gnueabihf ;;
esac
for lib in "${tmp_root}/usr/lib/${triplet}"/{blas/libblas,lapack/liblapack}.so.3; do
  [[ -e "${lib}" ]] || continue
  ln -sfn "$(basename "$(dirname "${lib}")")/$(basename "${lib}")" \
    "${tmp_root}/usr/lib/${triplet}/$(basename "${lib}")"
done

# Absolute symlinks (e.g. /lib/ld-linux-aarch64.so.1 -> /lib/aarch64-linux-gnu/ld-...) would
# point into the host; rewrite them relative so they resolve inside the sysroot, for the linker
# and for qemu -L (which would otherwise find the host's x86 files or nothing).
fixed=0
while IFS= read -r -d '' link; do
  target="$(readlink "${link}")"
  [[ "${target}" == /* ]] || continue
  ln -sfn "$(realpath -m -s --relative-to="$(dirname "${link}")" "${tmp_root}${target}")" "${link}"
  fixed=$((fixed + 1))
done < <(find "${tmp_root}" -type l -print0)
dangling="$(find "${tmp_root}" -xtype l | wc -l)"
log "rewrote ${fixed} absolute symlinks; ${dangling} dangling symlinks left"

rm -rf "${sysroot}"
mv "${tmp_root}" "${sysroot}"
echo "${stamp}" > "${stamp_file}"
log "ready: ${sysroot} ($(du -sh "${sysroot}" | cut -f1)) in $((SECONDS - start_s)) s"
