// Fuzz target: any decoded QR text is a tag or a refusal with a reason, never a crash; a text
// taken for a tag is exactly the payload that tag encodes to.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/cobot/tag.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::cobot;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  sen3bot::Result<Tag> tag = parse_tag(text);
  if (!tag) {
    if (tag.error().message().empty()) __builtin_trap();
    return 0;
  }
  if (tag->operator_id == 0 || tag->operator_id > kMaxOperatorId) __builtin_trap();
  sen3bot::Result<TagPayload> again = encode_tag(*tag);
  if (!again || again->text() != text) __builtin_trap();
  return 0;
}
