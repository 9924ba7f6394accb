# CMake toolchain file: 32-bit Raspberry Pi OS / Debian armhf (Raspberry Pi 3, 4, 5).
#
#   toolchain/sysroot.sh armhf
#   cmake -S . -B build-armhf -G Ninja \
#     -DCMAKE_TOOLCHAIN_FILE=toolchain/arm-linux-gnueabihf.cmake [-DSEN3BOT_CPU=generic-armv7-a]
#
# Same layout as aarch64-linux-gnu.cmake (read that file's notes): Debian's cross g++
# (g++-arm-linux-gnueabihf), libraries ONLY from the Debian armhf sysroot of toolchain/sysroot.sh
# (SEN3BOT_SYSROOT, else <repo>/.sysroot-armhf), tests under `qemu-arm -L <sysroot>`.
#
# Code generation: the Pi 3/4/5 cores run 32-bit ARMv8-A (AArch32) code, so the default is
# -mcpu=cortex-a53 -mfpu=neon-fp-armv8 -mfloat-abi=hard (NEON and VFPv4 on, hard-float ABI, the
# same ABI as Debian armhf and 32-bit Raspberry Pi OS). The libraries the binary links against
# on the Pi are Raspberry Pi OS's own (built for ARMv6 + VFP2); that is the same armhf ABI.
# For a Pi 2 (Cortex-A7, ARMv7-A) or broadest ARMv7 compatibility use
#   -DSEN3BOT_CPU=generic-armv7-a -DSEN3BOT_FPU=neon-vfpv4   (Pi 2 v1.1 and later)
# Boards without ARMv7 (Pi 1, Zero) are not supported.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(SEN3BOT_TARGET_TRIPLET arm-linux-gnueabihf)

set(SEN3BOT_CPU "cortex-a53" CACHE STRING "Target CPU for -mcpu (cortex-a53 = Pi 3, 4 and 5)")
set(SEN3BOT_FPU "neon-fp-armv8" CACHE STRING "Target FPU for -mfpu")

if(NOT SEN3BOT_SYSROOT)
  if(DEFINED ENV{SEN3BOT_SYSROOT} AND NOT "$ENV{SEN3BOT_SYSROOT}" STREQUAL "")
    set(SEN3BOT_SYSROOT "$ENV{SEN3BOT_SYSROOT}")
  else()
    get_filename_component(SEN3BOT_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../.sysroot-armhf" ABSOLUTE)
  endif()
endif()
set(SEN3BOT_SYSROOT "${SEN3BOT_SYSROOT}" CACHE PATH "Debian armhf sysroot (toolchain/sysroot.sh)")
if(NOT EXISTS "${SEN3BOT_SYSROOT}/lib/${SEN3BOT_TARGET_TRIPLET}/libc.so.6")
  message(FATAL_ERROR "No armhf sysroot at ${SEN3BOT_SYSROOT}: run toolchain/sysroot.sh armhf "
                      "(or point SEN3BOT_SYSROOT at one)")
endif()
# try_compile() projects read this file again; hand them the same settings.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES SEN3BOT_SYSROOT SEN3BOT_CPU SEN3BOT_FPU)

set(CMAKE_C_COMPILER ${SEN3BOT_TARGET_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${SEN3BOT_TARGET_TRIPLET}-g++)
set(CMAKE_SYSROOT "${SEN3BOT_SYSROOT}")

# -Wno-psabi: silences GCC's note that passing some std::vector iterators "changed in GCC 7.1";
# everything in bookworm and Raspberry Pi OS is built with GCC 12, so nothing mixes the two ABIs.
set(CMAKE_C_FLAGS_INIT "-mcpu=${SEN3BOT_CPU} -mfpu=${SEN3BOT_FPU} -mfloat-abi=hard -Wno-psabi")
set(CMAKE_CXX_FLAGS_INIT "-mcpu=${SEN3BOT_CPU} -mfpu=${SEN3BOT_FPU} -mfloat-abi=hard -Wno-psabi")
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

find_program(SEN3BOT_QEMU NAMES qemu-arm qemu-arm-static)
if(SEN3BOT_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${SEN3BOT_QEMU};-L;${SEN3BOT_SYSROOT};-E;SEN3BOT_QEMU_USER=1")
endif()
