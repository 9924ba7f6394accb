// Fuzz target: any bytes through the JSON reader give a document or an error with a reason,
// never a crash or a read past the input; what parses is walked, read back and rewritten.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/json/json.hpp"

namespace {

using namespace sen3bot::json;
using sen3bot::Status;

// Re-emits a value with the writer; the result must parse again.
void copy(Value v, Writer& w, int depth) {
  switch (v.type()) {
    case Type::null: w.null(); break;
    case Type::boolean: w.boolean(*v.boolean()); break;
    case Type::number: w.number(*v.number()); break;
    case Type::string: {
      std::array<char, 256> buf;
      auto n = v.string(buf);
      w.string(n ? std::string_view(buf.data(), *n) : std::string_view("long"));
      break;
    }
    case Type::array:
      w.begin_array();
      for (Value item : v.items()) copy(item, w, depth + 1);
      w.end_array();
      break;
    case Type::object:
      w.begin_object();
      for (Value::Member m : v.members()) {
        std::array<char, 256> buf;
        auto n = m.key.string(buf);
        w.key(n ? std::string_view(buf.data(), *n) : std::string_view("long"));
        copy(m.value, w, depth + 1);
      }
      w.end_object();
      break;
  }
  (void)v.uint32();
  (void)v.size();
  (void)v.find("key");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::json;
  using sen3bot::Status;
  static StaticDocument<4096> doc(Limits{24, 1 << 16});
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Status st = doc.parse(text);
  if (!st) {
    if (st.error().message().empty()) __builtin_trap();
    return 0;
  }
  // Long strings become "long" and keys may then repeat: only check structure when they do not.
  static std::array<char, 1 << 17> out;
  Writer w(out);
  copy(doc.root(), w, 0);
  auto written = w.finish();
  if (!written) {
    if (written.error().code() != sen3bot::Errc::capacity) __builtin_trap();
    return 0;
  }
  static StaticDocument<4096> again(Limits{24, 1 << 17});
  Status st2 = again.parse(*written);
  if (!st2 && st2.error().message().find("duplicate") == std::string_view::npos) __builtin_trap();
  return 0;
}
