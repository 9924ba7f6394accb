# Tags: the payload (pure), its fuzz target; the QR reader on simulated frames, the printable
# tags and `sen3bot cobot tags` (where OpenCV's objdetect is).
sen3bot_test(cobot_tag_tests
  SOURCES tag_test.cpp
  LIBS sen3bot_cobot_tag
  LABELS cobot)

sen3bot_fuzz_target(cobot_tag
  SOURCE fuzz_tag.cpp
  CORPUS ${PROJECT_SOURCE_DIR}/tests/data/fuzz/cobot_tag
  LIBS sen3bot_cobot_tag)

if(TARGET sen3bot_cobot_qr AND TARGET OpenCV::imgcodecs)
  sen3bot_test(cobot_qr_tests
    SOURCES qr_reader_test.cpp
    LIBS sen3bot_cobot_qr sen3bot_sim_tag_scene OpenCV::objdetect OpenCV::imgcodecs OpenCV::imgproc OpenCV::core
    LABELS cobot
    TIMEOUT 300)
  sen3bot_test(cobot_command_tests
    SOURCES cobot_command_test.cpp
    LIBS sen3bot_qr_row OpenCV::imgcodecs OpenCV::core
    LABELS cobot firmware)
  target_include_directories(cobot_command_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)
endif()
