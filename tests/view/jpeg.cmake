# The JPEG encoder: decoded by the system libjpeg where it is (the independent decoder); the
# capacity, argument and allocation checks run everywhere, cross builds included.
find_package(JPEG QUIET)
set(view_jpeg_test_libs sen3bot_view_jpeg sen3bot_alloc_counter)
if(TARGET JPEG::JPEG)
  list(APPEND view_jpeg_test_libs JPEG::JPEG)
endif()
sen3bot_test(view_jpeg_tests SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/jpeg_test.cpp LIBS ${view_jpeg_test_libs} LABELS view)
if(TARGET JPEG::JPEG)
  target_compile_definitions(view_jpeg_tests PRIVATE SEN3BOT_HAVE_LIBJPEG=1)
endif()

# 640 x 480 colour and 320 x 240 grey per encode (prints numbers; not a test).
if(SEN3BOT_BENCH)
  find_package(benchmark QUIET)
  if(TARGET benchmark::benchmark)
    add_executable(sen3bot_jpeg_bench ${CMAKE_CURRENT_SOURCE_DIR}/jpeg_bench.cpp)
    target_link_libraries(sen3bot_jpeg_bench PRIVATE sen3bot_view_jpeg benchmark::benchmark)
  endif()
endif()
