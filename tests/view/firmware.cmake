# The live view in the whole firmware on the simulated robot.
if(TARGET sen3bot_view_server AND TARGET sen3bot_sim)
  sen3bot_test(view_firmware_tests
    SOURCES firmware_view_test.cpp
    LIBS sen3bot_firmware sen3bot_sim
    LABELS "view;slow;timing"
    TIMEOUT 180
    RUN_SERIAL)
  target_include_directories(view_firmware_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)
endif()

# The view row alone and the `view` section.
if(TARGET sen3bot_firmware_core)
  sen3bot_test(view_task_tests
    SOURCES view_task_test.cpp
    LIBS sen3bot_firmware_core
    LABELS view)
endif()
