// A client's messages to the live view: any text must leave the session consistent, and every
// reply must be a complete status message.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "sen3bot/json/json.hpp"
#include "sen3bot/view/session.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::view;
  static Session session;
  session.reset(5);
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  session.on_text(text);
  session.on_binary({data, size});
  static sen3bot::json::StaticDocument<64> reply;
  while (session.has_reply()) {
    if (!reply.parse(session.reply()) || !reply.root().find("op").string_equals("status")) std::abort();
    session.pop_reply();
  }
  for (std::size_t c = 0; c < 5; ++c) {
    const std::uint32_t id = session.subscription(c);
    if (id == Session::kNone) continue;
    for (std::size_t d = c + 1; d < 5; ++d)
      if (session.subscription(d) == id) std::abort();  // one id, one channel
  }
  return 0;
}
