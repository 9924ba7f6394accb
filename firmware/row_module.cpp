#include "row_module.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace sen3bot::firmware {
namespace {

std::vector<std::string> module_dirs() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("SEN3BOT_MODULE_DIR"); env != nullptr && *env != '\0') dirs.emplace_back(env);
  char exe[4096];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  const std::string path = n > 0 ? std::string(exe, static_cast<std::size_t>(n)) : std::string();
  if (const std::size_t slash = path.find_last_of('/'); slash != std::string::npos) {
    const std::string dir = path.substr(0, slash);
    dirs.push_back(dir);
    dirs.push_back(dir + "/../lib/sen3bot");
  }
#ifdef SEN3BOT_MODULE_BUILD_DIR
  dirs.emplace_back(SEN3BOT_MODULE_BUILD_DIR);
#endif
  return dirs;
}

Result<const RowModule*> open_module(const std::string& file) {
  std::string searched;
  for (const std::string& dir : module_dirs()) {
    const std::string path = dir + "/" + file;
    if (::access(path.c_str(), F_OK) != 0) {
      searched += searched.empty() ? dir : ", " + dir;
      continue;
    }
    void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) return Error::format(Errc::io, "%s", ::dlerror());
    using Entry = const RowModule* (*)();
    auto entry = reinterpret_cast<Entry>(::dlsym(handle, "sen3bot_row_module"));
    const RowModule* module = entry != nullptr ? entry() : nullptr;
    const RowModule expected;
    if (module == nullptr || module->abi != expected.abi || module->camera_size != expected.camera_size ||
        module->vision_size != expected.vision_size || module->qr_size != expected.qr_size ||
        module->recognition_size != expected.recognition_size || module->version == nullptr ||
        std::strcmp(module->version, SEN3BOT_VERSION) != 0) {
      ::dlclose(handle);
      return Error::format(Errc::not_supported, "%s: built for another version of the firmware; rebuild it", path.c_str());
    }
    return module;  // never closed: the rows it built run its code
  }
  return Error::format(Errc::not_found, "%s not found (looked in %s); build it with the firmware or install it next to the binary",
                       file.c_str(), searched.c_str());
}

}  // namespace

Result<const RowModule*> load_row_module(const char* name) {
  static std::mutex mutex;
  static std::map<std::string, const RowModule*> loaded;
  const std::lock_guard<std::mutex> lock(mutex);
  const std::string file = std::string("sen3bot-") + name + ".so";
  if (auto it = loaded.find(file); it != loaded.end()) return it->second;
  Result<const RowModule*> module = open_module(file);
  if (module) loaded.emplace(file, *module);
  return module;
}

int row_module_command(const char* module, const char* program, int argc, char** argv, std::FILE* out,
                       std::FILE* err) {
  Result<const RowModule*> loaded = load_row_module(module);
  if (!loaded) {
    std::fprintf(err, "%s: %s\n", program, loaded.error().c_str());
    return 2;
  }
  return (*loaded)->command(argc, argv, out, err);
}

}  // namespace sen3bot::firmware
