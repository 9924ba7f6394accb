# Finds the individual OpenCV module libraries that Debian ships as libopencv-<module>-dev.
#
# Debian installs OpenCVConfig.cmake only with the libopencv-dev meta package, which pulls in
# every module (video, dnn, contrib, ...). The firmware uses only a few modules, so it depends
# on those packages alone and finds their headers and libraries here. This also keeps the
# aarch64 cross sysroot small.
#
# Input:  COMPONENTS core imgproc imgcodecs ...
# Output: OpenCVModules_FOUND, OpenCVModules_<c>_FOUND, imported targets OpenCV::<c>.
include(FindPackageHandleStandardArgs)

find_path(OpenCVModules_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
foreach(component IN LISTS OpenCVModules_FIND_COMPONENTS)
  find_library(OpenCVModules_${component}_LIBRARY NAMES opencv_${component})
  if(OpenCVModules_INCLUDE_DIR AND OpenCVModules_${component}_LIBRARY)
    set(OpenCVModules_${component}_FOUND TRUE)
    if(NOT TARGET OpenCV::${component})
      add_library(OpenCV::${component} UNKNOWN IMPORTED)
      set_target_properties(OpenCV::${component} PROPERTIES
        IMPORTED_LOCATION "${OpenCVModules_${component}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OpenCVModules_INCLUDE_DIR}")
    endif()
  else()
    set(OpenCVModules_${component}_FOUND FALSE)
  endif()
endforeach()

find_package_handle_standard_args(OpenCVModules
  REQUIRED_VARS OpenCVModules_INCLUDE_DIR
  HANDLE_COMPONENTS)
