# The collaborative mode's decision cores (cobot/core): trigger, mode, follow-me, path recorder.
sen3bot_test(cobot_core_tests
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/trigger_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/mode_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/follow_test.cpp
    ${CMAKE_CURRENT_LIST_DIR}/path_recorder_test.cpp
  LIBS sen3bot_cobot sen3bot_alloc_counter
  LABELS cobot)
