# Project-wide compile options, applied through the sen3bot_options interface target so
# every library, test and tool is built the same way.
add_library(sen3bot_options INTERFACE)
target_compile_options(sen3bot_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wnon-virtual-dtor -Woverloaded-virtual -Wimplicit-fallthrough)
if(SEN3BOT_WERROR)
  target_compile_options(sen3bot_options INTERFACE -Werror)
endif()
if(SEN3BOT_SANITIZE)
  target_compile_options(sen3bot_options INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC 12 reports false maybe-uninitialized warnings in sanitizer-instrumented code.
    target_compile_options(sen3bot_options INTERFACE -Wno-maybe-uninitialized)
  endif()
  target_link_options(sen3bot_options INTERFACE -fsanitize=address,undefined)
  target_compile_definitions(sen3bot_options INTERFACE SEN3BOT_SANITIZED=1)
  if(SEN3BOT_LIBFUZZER)
    # One tree for the sanitized suite and the fuzzers: everything carries libFuzzer's coverage
    # counters, so the parsers' own branches guide the search, and the tests link without the
    # fuzzer's main (the sanitizer runtime defines the counters' hooks).
    target_compile_options(sen3bot_options INTERFACE -fsanitize=fuzzer-no-link)
  endif()
endif()
if(SEN3BOT_LIBFUZZER AND NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  message(FATAL_ERROR "SEN3BOT_LIBFUZZER needs clang 16 or later (CC=clang-16 CXX=clang++-16)")
endif()

# Every library in the tree: static, position independent, with the project options.
function(sen3bot_library name)
  add_library(${name} STATIC ${ARGN})
  target_link_libraries(${name} PUBLIC sen3bot_options)
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON
                                           UNITY_BUILD ${SEN3BOT_UNITY_BUILD})
  if(SEN3BOT_UNITY_BUILD AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # In a batch a source's private types are no longer in the main file, and GCC warns about
    # every class that holds one; one source per compile (the option off) keeps the check.
    target_compile_options(${name} PRIVATE -Wno-subobject-linkage)
  endif()
endfunction()
