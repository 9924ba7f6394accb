// The object the tests' shared precompiled header is built for (tests/CMakeLists.txt).
