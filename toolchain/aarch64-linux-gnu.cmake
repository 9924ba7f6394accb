# CMake toolchain file: 64-bit Raspberry Pi OS / Debian arm64 (Raspberry Pi 3, 4, 5).
#
#   toolchain/sysroot.sh aarch64
#   cmake -S . -B build-aarch64 -G Ninja \
#     -DCMAKE_TOOLCHAIN_FILE=toolchain/aarch64-linux-gnu.cmake [-DSEN3BOT_CPU=cortex-a72]
#
# Compilers: Debian's cross g++ (g++-aarch64-linux-gnu). Its own libc/libstdc++ headers and
# link-time libraries live in /usr/aarch64-linux-gnu and are searched first; every other
# library and CMake package is looked up ONLY in the sysroot built by toolchain/sysroot.sh
# (SEN3BOT_SYSROOT: cache variable, else the environment variable, else <repo>/.sysroot-aarch64).
# Both come from the same bookworm glibc 2.36 / GCC 12, so the binary runs on the Pi.
#
# Test programs run through qemu-user (CMAKE_CROSSCOMPILING_EMULATOR): `qemu-aarch64 -L
# <sysroot>` makes the program's loader /lib/ld-linux-aarch64.so.1 and every library it opens
# resolve inside the sysroot first, so the dynamic loader and libc.so.6 always come as one pair
# from the sysroot's libc6 package (never the cross toolchain's loader with another libc).
# Paths that do not exist in the sysroot (the build and source trees) fall back to the host.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(SEN3BOT_TARGET_TRIPLET aarch64-linux-gnu)

# -mcpu: Cortex-A53 is the Pi 3's core; code tuned for it runs on the Pi 4 (A72) and Pi 5 (A76).
# Override for a single board, e.g. -DSEN3BOT_CPU=cortex-a76 for a Pi 5 only.
set(SEN3BOT_CPU "cortex-a53" CACHE STRING "Target CPU for -mcpu (cortex-a53 = Pi 3, 4 and 5)")

if(NOT SEN3BOT_SYSROOT)
  if(DEFINED ENV{SEN3BOT_SYSROOT} AND NOT "$ENV{SEN3BOT_SYSROOT}" STREQUAL "")
    set(SEN3BOT_SYSROOT "$ENV{SEN3BOT_SYSROOT}")
  else()
    get_filename_component(SEN3BOT_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../.sysroot-aarch64" ABSOLUTE)
  endif()
endif()
set(SEN3BOT_SYSROOT "${SEN3BOT_SYSROOT}" CACHE PATH "Debian arm64 sysroot (toolchain/sysroot.sh)")
if(NOT EXISTS "${SEN3BOT_SYSROOT}/lib/${SEN3BOT_TARGET_TRIPLET}/libc.so.6")
  message(FATAL_ERROR "No arm64 sysroot at ${SEN3BOT_SYSROOT}: run toolchain/sysroot.sh aarch64 "
                      "(or point SEN3BOT_SYSROOT at one)")
endif()
# try_compile() projects read this file again; hand them the same settings.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES SEN3BOT_SYSROOT SEN3BOT_CPU)

set(CMAKE_C_COMPILER ${SEN3BOT_TARGET_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${SEN3BOT_TARGET_TRIPLET}-g++)
set(CMAKE_SYSROOT "${SEN3BOT_SYSROOT}")

set(CMAKE_C_FLAGS_INIT "-mcpu=${SEN3BOT_CPU}")
set(CMAKE_CXX_FLAGS_INIT "-mcpu=${SEN3BOT_CPU}")
# Let the linker find the dependencies of the sysroot's shared libraries (libopencv_core ->
# libtbb, libblas, ...) that the program does not name itself.
set(_sen3bot_rpath_link
  "-Wl,-rpath-link,${SEN3BOT_SYSROOT}/lib/${SEN3BOT_TARGET_TRIPLET}:${SEN3BOT_SYSROOT}/usr/lib/${SEN3BOT_TARGET_TRIPLET}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${_sen3bot_rpath_link}")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "${_sen3bot_rpath_link}")
set(CMAKE_MODULE_LINKER_FLAGS_INIT "${_sen3bot_rpath_link}")

set(CMAKE_FIND_ROOT_PATH "${SEN3BOT_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config (for later GStreamer/libav dependencies) must read the sysroot's .pc files.
set(ENV{PKG_CONFIG_DIR} "")
set(ENV{PKG_CONFIG_LIBDIR}
  "${SEN3BOT_SYSROOT}/usr/lib/${SEN3BOT_TARGET_TRIPLET}/pkgconfig:${SEN3BOT_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${SEN3BOT_SYSROOT}")

find_program(SEN3BOT_QEMU NAMES qemu-aarch64 qemu-aarch64-static)
if(SEN3BOT_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${SEN3BOT_QEMU};-L;${SEN3BOT_SYSROOT};-E;SEN3BOT_QEMU_USER=1")
endif()
