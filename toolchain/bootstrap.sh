#!/usr/bin/env bash
# Installs, with apt-get, every Debian 12 (bookworm) package that building and testing Sen3Bot
# needs. Idempotent: packages already installed are skipped (checked with dpkg-query), and apt
# is not even started when nothing is missing, so a second run takes well under a second.
#
#   toolchain/bootstrap.sh [--mission] [--cross] [--deploy] [--dry-run]
#
#   (none)     native build, tests, benchmarks, sanitizers and the optional libFuzzer build
#   --mission  only what building the simulated robot needs (the README's mission command):
#              the compilers and the firmware's libraries, none of the tests' peers and tools
#   --cross    also the Raspberry Pi cross build: cross compilers, qemu-user, and the tools
#              toolchain/sysroot.sh uses to assemble the arm64/armhf sysroot
#   --deploy   also what toolchain/deploy.sh uses (ssh/scp, rsync)
#   --dry-run  print what would be installed, install nothing
#
# Runs as root directly, or through sudo when started by another user. Non-interactive.
# Later work adds its packages to the lists below (one per line, a comment saying who needs it).
set -euo pipefail

# --- Building the firmware and the simulator (--mission installs only these) -----------------
BUILD_PACKAGES=(
  build-essential            # gcc/g++ 12, make, libc6-dev
  g++
  cmake                      # >= 3.25 (bookworm: 3.25.1)
  ninja-build
  ccache                     # the test command's builds reuse objects from earlier runs
  pkgconf                    # pkg-config, for dependencies without CMake packages
  libyaml-cpp-dev
  libeigen3-dev              # map building: the pose graph's sparse Cholesky (headers only)
  zlib1g-dev                 # map building: gzipped CARMEN logs
  libopencv-core-dev
  libopencv-imgproc-dev
  libjpeg62-turbo-dev        # camera: JPEG frames, `sen3bot detect --image` (libjpeg-turbo)
  libpng-dev                 # PNG figures and saved frames
  libopencv-objdetect-dev    # the on-board people detector (HOG), the QR tag reader
  libopencv-ml-dev           # operation recognition: the worker-path classifier (an MLP)
  libssl-dev                 # camera: MD5 for RTSP Digest auth (libcrypto)
  libavcodec-dev             # camera: H.264 decoding
  libavutil-dev
  libswscale-dev             # camera: YUV -> BGR/grey and downscaling
  libpugixml-dev             # camera: ONVIF SOAP replies (no DTD, no external entities)
  libcurl4-openssl-dev       # camera: ONVIF over HTTP (chunked bodies, HTTP Digest)
  libmosquitto-dev           # fleet: the MQTT client (Eclipse Mosquitto's libmosquitto)
  libwebsockets-dev          # view: the live view's WebSocket + HTTP server
)

# --- Tests, benchmarks, sanitizers and fuzzing ------------------------------------------------
TEST_PACKAGES=(
  libgtest-dev
  libgmock-dev
  libbenchmark-dev
  libopencv-imgcodecs-dev    # tests only: the firmware's JPEG/PNG are checked against OpenCV's codecs
  opencv-doc                 # its tests: the people in OpenCV's sample images (Apache-2.0)
  rt-tests                   # cyclictest, compared against by the jitter benchmark
  clang-16                   # the sanitized suite and the bounded libFuzzer run (SEN3BOT_LIBFUZZER=ON);
                             # 16: the first with C++20's conditionally trivial members (StaticVector)
  libclang-rt-16-dev         # libFuzzer and the sanitizer runtimes for clang 16
  llvm-16                    # llvm-symbolizer: file:line in the sanitizers' reports
  libmrpt-hwdrivers-dev      # lms200 tests: MRPT's CSickLaserSerial, a third-party LMS200 client
  python3-jsonschema         # vda5050 tests: encoder output checked against the VDA 5050 JSON schemas
  python3-gi                 # camera tests: the RTSP peer is gst-rtsp-server driven from Python
  python3-gst-1.0
  gir1.2-gst-rtsp-server-1.0
  gstreamer1.0-rtsp
  gstreamer1.0-plugins-base  # videotestsrc, jpegenc
  gstreamer1.0-plugins-good  # rtph264pay, rtpjpegpay
  gstreamer1.0-plugins-ugly  # x264enc
  ffmpeg                     # camera tests: ffprobe cross-checks what the peer streams
  tshark                     # camera tests: the checked-in RTSP capture must dissect
  libjpeg-turbo-progs        # camera tests: cjpeg makes restart-marker JPEGs for the type 65 peer
  mosquitto                  # fleet tests: the real broker, with the shipped TLS + ACL configuration
  openssl                    # fleet tests: toolchain/broker-pki.sh makes the test CA
  chromium                   # view tests: the built-in page in a headless browser
)

# vda5050 peer test (tests/peers/vda5050) and the view's tests (tests/view): Node.js and npm run
# the independent master control, the Foxglove client and the browser driver.
# Debian's (nodejs 18, npm 9) only when none is on PATH: a Node.js installed otherwise is kept.
if ! command -v node >/dev/null; then TEST_PACKAGES+=(nodejs); fi
if ! command -v npm >/dev/null; then TEST_PACKAGES+=(npm); fi

# --- Raspberry Pi cross build (--cross) -------------------------------------------------------
CROSS_PACKAGES=(
  g++-aarch64-linux-gnu      # 64-bit Raspberry Pi OS (Pi 3/4/5)
  g++-arm-linux-gnueabihf    # 32-bit Raspberry Pi OS
  qemu-user                  # runs the cross-built tests (qemu-aarch64, qemu-arm)
  apt                        # sysroot.sh: private apt (download only)
  dpkg                       # sysroot.sh: dpkg-deb -x
  debian-archive-keyring     # sysroot.sh: verifies the mirror's Release files
  ca-certificates            # https mirrors
  coreutils                  # sha256sum, realpath
  findutils
)

# --- Deployment to the robot (--deploy) -------------------------------------------------------
DEPLOY_PACKAGES=(
  openssh-client             # ssh, scp
  rsync
)
# ----------------------------------------------------------------------------------------------

want_mission=0
want_cross=0
want_deploy=0
dry_run=0
for arg in "$@"; do
  case "${arg}" in
    --mission) want_mission=1 ;;
    --cross) want_cross=1 ;;
    --deploy) want_deploy=1 ;;
    --dry-run) dry_run=1 ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "bootstrap.sh: unknown argument '${arg}'" >&2; exit 2 ;;
  esac
done

packages=("${BUILD_PACKAGES[@]}")
if [[ "${want_mission}" == 0 ]]; then packages+=("${TEST_PACKAGES[@]}"); fi
if [[ "${want_cross}" == 1 ]]; then packages+=("${CROSS_PACKAGES[@]}"); fi
if [[ "${want_deploy}" == 1 ]]; then packages+=("${DEPLOY_PACKAGES[@]}"); fi

if ! command -v dpkg-query >/dev/null || ! command -v apt-get >/dev/null; then
  echo "bootstrap.sh: needs a Debian-based system (dpkg-query and apt-get)" >&2
  exit 1
fi

# One dpkg-query call for the whole list; packages it does not know are reported on stderr.
declare -A installed=()
while IFS=' ' read -r name status; do
  [[ "${status}" == installed ]] && installed["${name%%:*}"]=1
done < <(dpkg-query -W -f='${Package} ${db:Status-Status}\n' "${packages[@]}" 2>/dev/null || true)

missing=()
for pkg in "${packages[@]}"; do
  [[ -n "${installed[${pkg}]:-}" ]] || missing+=("${pkg}")
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "bootstrap: all ${#packages[@]} packages already installed"
  exit 0
fi
echo "bootstrap: installing ${#missing[@]} package(s): ${missing[*]}"
if [[ "${dry_run}" == 1 ]]; then
  exit 0
fi

as_root=()
if [[ "$(id -u)" != 0 ]]; then
  if command -v sudo >/dev/null; then
    as_root=(sudo)
  else
    echo "bootstrap.sh: not root and no sudo; run it as root" >&2
    exit 1
  fi
fi

export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -q
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q \
  --no-install-recommends "${missing[@]}"
echo "bootstrap: installed ${missing[*]}"
