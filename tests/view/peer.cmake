# Independent peers of the live view (docs/view.md), each against `sen3bot-sim sim --view` in
# real time. Native builds only: the simulator runs on this machine beside the peer.
if(NOT CMAKE_CROSSCOMPILING AND TARGET sen3bot-sim)
  # The official Foxglove client (@foxglove/ws-protocol over ws) checks the protocol, every
  # channel's messages against the advertised schema and @foxglove/schemas' official one, and
  # their meaning. The npm packages of tests/view/peer/package-lock.json are installed once
  # into the build tree (again only when the lock file changes). Skipped (exit 77) without
  # node or npm.
  add_test(NAME view.peer.foxglove_client
    COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/peer/run_view_peer.py
            --sim $<TARGET_FILE:sen3bot-sim>
            --cache ${CMAKE_CURRENT_BINARY_DIR}/view-npm
            --source-dir ${PROJECT_SOURCE_DIR})
  set(labels view peer npm timing)
  sen3bot_peer_labels(labels)
  set_tests_properties(view.peer.foxglove_client PROPERTIES
    LABELS "${labels}"
    TIMEOUT 300
    SKIP_RETURN_CODE 77
    RESOURCE_LOCK view-npm)

  # Hostile peers (Python's standard library only): garbage, malformed frames, an oversized
  # message, operations the server does not accept, the wrong subprotocol, a client that stops
  # reading, and the token of a non-loopback address; a well-behaved client beside them must
  # keep its rate and the tasks their deadlines: run alone, as another test's load would
  # cost the tasks deadlines too.
  add_test(NAME view.peer.hostile
    COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/peer/hostile_peers.py
            --sim $<TARGET_FILE:sen3bot-sim>
            --source-dir ${PROJECT_SOURCE_DIR})
  set(labels view peer timing)
  sen3bot_peer_labels(labels)
  set_tests_properties(view.peer.hostile PROPERTIES
    LABELS "${labels}"
    TIMEOUT 300
    SKIP_RETURN_CODE 77
    RUN_SERIAL TRUE)
endif()
