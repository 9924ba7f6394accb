# The live view's pure encoders: every Foxglove message read back with the robot's own JSON
# reader and checked against the advertised schema, overflow, no allocation.
if(TARGET sen3bot_view_core)
  sen3bot_test(view_core_tests
    SOURCES core_test.cpp
    LIBS sen3bot_view_core sen3bot_alloc_counter
    LABELS view)
endif()
