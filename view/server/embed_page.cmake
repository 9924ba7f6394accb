# Writes OUT, a C++ source holding IN's bytes as sen3bot::view::kViewPage.
file(READ ${IN} hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "((0x[0-9a-f][0-9a-f],){24})" "\\1\n" bytes "${bytes}")
file(WRITE ${OUT} "// Generated from view/page/index.html at build time.\n#include <cstddef>\nnamespace sen3bot::view {\nextern const unsigned char kViewPage[];\nextern const std::size_t kViewPageSize;\nconst unsigned char kViewPage[] = {\n${bytes}};\nconst std::size_t kViewPageSize = ${size};\n}  // namespace sen3bot::view\n")
