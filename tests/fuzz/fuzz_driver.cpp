// Runs a fuzz target without libFuzzer: every file of the corpus, then a deterministic batch of
// mutations of those files (bit flips, byte sets, insertions, deletions, truncations, splices).
// Crashes, sanitizer reports and failed assertions inside the target fail the test.
//
// usage: <target> <corpus-dir-or-file>... [--mutations N] [--seed S]
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void run(const Bytes& input) { LLVMFuzzerTestOneInput(input.data(), input.size()); }

Bytes mutate(const std::vector<Bytes>& corpus, std::mt19937_64& rng) {
  Bytes out = corpus.empty() ? Bytes{} : corpus[rng() % corpus.size()];
  const int edits = 1 + static_cast<int>(rng() % 8);
  for (int e = 0; e < edits; ++e) {
    switch (rng() % 6) {
      case 0:  // flip one bit
        if (!out.empty()) out[rng() % out.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
        break;
      case 1:  // set a byte to an interesting or random value
        if (!out.empty()) {
          static constexpr std::uint8_t kInteresting[] = {0x00, 0x01, 0x02, 0x7F, 0x80, 0xFA, 0xFB, 0xFF};
          out[rng() % out.size()] = (rng() % 2) ? kInteresting[rng() % sizeof kInteresting]
                                                : static_cast<std::uint8_t>(rng());
        }
        break;
      case 2: {  // insert random bytes
        const std::size_t at = out.empty() ? 0 : rng() % (out.size() + 1);
        const std::size_t n = 1 + rng() % 16;
        for (std::size_t i = 0; i < n; ++i) out.insert(out.begin() + static_cast<long>(at), static_cast<std::uint8_t>(rng()));
        break;
      }
      case 3:  // delete a range
        if (!out.empty()) {
          const std::size_t at = rng() % out.size();
          const std::size_t n = 1 + rng() % (out.size() - at);
          out.erase(out.begin() + static_cast<long>(at), out.begin() + static_cast<long>(at + n));
        }
        break;
      case 4:  // truncate
        if (!out.empty()) out.resize(rng() % out.size());
        break;
      case 5:  // splice in part of another corpus entry
        if (!corpus.empty()) {
          const Bytes& other = corpus[rng() % corpus.size()];
          if (!other.empty()) {
            const std::size_t from = rng() % other.size();
            const std::size_t at = out.empty() ? 0 : rng() % (out.size() + 1);
            out.insert(out.begin() + static_cast<long>(at), other.begin() + static_cast<long>(from), other.end());
          }
        }
        break;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<Bytes> corpus;
  long mutations = 0;
  unsigned long long seed = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--mutations") == 0 && i + 1 < argc) {
      mutations = std::atol(argv[++i]);
    } else if (std::strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else {
      const std::filesystem::path path(argv[i]);
      if (std::filesystem::is_directory(path)) {
        std::vector<std::filesystem::path> files;
        for (const auto& entry : std::filesystem::directory_iterator(path))
          if (entry.is_regular_file()) files.push_back(entry.path());
        std::sort(files.begin(), files.end());  // deterministic order
        for (const auto& f : files) corpus.push_back(read_file(f));
      } else if (std::filesystem::is_regular_file(path)) {
        corpus.push_back(read_file(path));
      } else {
        std::fprintf(stderr, "fuzz driver: no such corpus path: %s\n", argv[i]);
        return 2;
      }
    }
  }
  run(Bytes{});
  for (const Bytes& input : corpus) run(input);
  std::mt19937_64 rng(seed);
  for (long i = 0; i < mutations; ++i) run(mutate(corpus, rng));
  std::printf("fuzz driver: %zu corpus inputs, %ld mutations, seed %llu: no failure\n", corpus.size(), mutations, seed);
  return 0;
}
