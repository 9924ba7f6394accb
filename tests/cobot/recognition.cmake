# Operation recognition (cobot/recognition): the operations file, the path features and the
# paths file; the simulated workers; the shipped model on held-out workers; `sen3bot recognize`;
# fuzz targets for the two text formats read from outside.
sen3bot_test(cobot_operations_tests
  SOURCES operations_test.cpp features_test.cpp path_file_test.cpp
  LIBS sen3bot_cobot_operations sen3bot_alloc_counter
  LABELS cobot)

sen3bot_test(cobot_workers_tests
  SOURCES workers_test.cpp
  LIBS sen3bot_sim_workers
  LABELS cobot)

if(TARGET sen3bot_cobot_recognizer)
  # Held-out walks per operation for the shipped model's test: fewer under qemu (~10x slower).
  if(CMAKE_CROSSCOMPILING)
    set(held_out_walks 10)
  else()
    set(held_out_walks 20)
  endif()
  sen3bot_test(cobot_recognizer_tests
    SOURCES recognizer_test.cpp
    LIBS sen3bot_cobot_recognizer sen3bot_sim_workers
    LABELS cobot
    TIMEOUT 300)
  target_compile_definitions(cobot_recognizer_tests PRIVATE SEN3BOT_HELD_OUT_WALKS=${held_out_walks})

  sen3bot_test(cobot_recognize_command_tests
    SOURCES recognize_command_test.cpp
    LIBS sen3bot_recognition_row
    LABELS cobot firmware)
  target_include_directories(cobot_recognize_command_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)
endif()

sen3bot_fuzz_target(cobot_paths
  SOURCE fuzz_cobot_paths.cpp
  CORPUS ${PROJECT_SOURCE_DIR}/tests/data/fuzz/cobot_paths
  LIBS sen3bot_cobot_operations)

sen3bot_fuzz_target(cobot_operations
  SOURCE fuzz_cobot_operations.cpp
  CORPUS ${PROJECT_SOURCE_DIR}/tests/data/fuzz/cobot_operations
  LIBS sen3bot_cobot_operations)
