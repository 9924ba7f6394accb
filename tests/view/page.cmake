# The built-in page (view/page/index.html) in headless Chromium through playwright-core (npm,
# drives Debian's /usr/bin/chromium and downloads no browser) against the simulator's view:
# connected, the map, pose and mission decoded, the pose the report's final one, the robot and
# the walls on the canvas, nothing fetched from another origin, no console errors; desktop and
# phone viewports. The npm packages of tests/view/page/package-lock.json are installed once
# into the build tree (again only when the lock file changes). Native builds only; skipped
# (exit 77) without node, npm or Chromium. Screenshots: BUILD/tests/view/page-report/run/.
if(NOT CMAKE_CROSSCOMPILING AND TARGET sen3bot-sim)
  add_test(NAME view.page.browser
    COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/page/run_page_test.py
            --sim $<TARGET_FILE:sen3bot-sim>
            --cache ${CMAKE_CURRENT_BINARY_DIR}/page-npm
            --source-dir ${PROJECT_SOURCE_DIR}
            --out ${CMAKE_CURRENT_BINARY_DIR}/page-report
            --timeout 120)
  set(labels view peer npm browser)
  sen3bot_peer_labels(labels)
  set_tests_properties(view.page.browser PROPERTIES
    LABELS "${labels}"
    TIMEOUT 300
    SKIP_RETURN_CODE 77
    RESOURCE_LOCK view-page-npm)
endif()
