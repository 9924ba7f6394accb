# The server without the firmware: the board, the protocol's client operations, and the server
# over real sockets on loopback (and this machine's own address for the token).
if(TARGET sen3bot_view_server)
  sen3bot_test(view_server_tests
    SOURCES server_test.cpp
    LIBS sen3bot_view_server sen3bot_alloc_counter
    LABELS view timing
    TIMEOUT 120)
  target_include_directories(view_server_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)

  # What a client sends: any bytes as one text message, and as a binary one.
  sen3bot_fuzz_target(view_client_ops
    SOURCE fuzz_client_ops.cpp
    CORPUS ${PROJECT_SOURCE_DIR}/tests/data/fuzz/view_client_ops
    LIBS sen3bot_view_server)
endif()
