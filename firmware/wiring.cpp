#include "wiring.hpp"

#include <algorithm>
#include <map>

#include "task_table.hpp"

namespace sen3bot::firmware {

void Wiring::note(std::vector<std::string>& list, std::string_view name) {
  if (std::find(list.begin(), list.end(), name) == list.end()) list.emplace_back(name);
}

tasks::Task* Wiring::uses(std::string_view name) {
  for (std::size_t i = 0; i < current_; ++i)
    if (rows_[i].name == name && tasks_[i] != nullptr) {
      note(row().uses, name);
      return tasks_[i].get();
    }
  return nullptr;
}

bool Wiring::runs(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < current_; ++i)
    if (rows_[i].name == name) return tasks_[i] != nullptr;
  return false;
}

namespace {

const tasks::TaskSpec& spec_of(std::string_view name) {
  for (const Row& r : kRows)
    if (r.spec.name == name) return r.spec;
  return kRows[0].spec;  // every RowWiring comes from the table
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "-" : out;
}

std::string period(std::int64_t us) {
  char text[32];
  if (us % 1000 == 0) std::snprintf(text, sizeof text, "%lld ms", static_cast<long long>(us / 1000));
  else std::snprintf(text, sizeof text, "%.1f ms", static_cast<double>(us) / 1000.0);
  return text;
}

}  // namespace

void print_graph(std::span<const RowWiring> rows, std::FILE* out) {
  // Threads in the order their first row appears in the table.
  std::vector<std::string_view> threads;
  for (const RowWiring& r : rows)
    if (r.absent.empty() && std::find(threads.begin(), threads.end(), spec_of(r.name).thread) == threads.end())
      threads.push_back(spec_of(r.name).thread);
  std::fprintf(out, "rows, by thread (each: every period, in table order):\n");
  for (std::string_view thread : threads) {
    std::fprintf(out, "\nthread %.*s\n", static_cast<int>(thread.size()), thread.data());
    for (const RowWiring& r : rows) {
      const tasks::TaskSpec& spec = spec_of(r.name);
      if (!r.absent.empty() || spec.thread != thread) continue;
      std::fprintf(out, "  %-12.*s every %s, budget %s\n", static_cast<int>(r.name.size()), r.name.data(),
                   period(spec.period_us).c_str(), period(spec.budget_us).c_str());
      for (const std::string& d : r.devices) std::fprintf(out, "      %s\n", d.c_str());
      if (!r.reads.empty()) std::fprintf(out, "      reads  %s\n", joined(r.reads).c_str());
      if (!r.writes.empty()) std::fprintf(out, "      writes %s\n", joined(r.writes).c_str());
      if (!r.uses.empty()) std::fprintf(out, "      uses   %s (its state, on the same thread or by its own lock)\n",
                                        joined(r.uses).c_str());
    }
  }
  // Each topic: who writes it, who reads it.
  std::map<std::string, std::pair<std::vector<std::string>, std::vector<std::string>>> topics;
  for (const RowWiring& r : rows) {
    for (const std::string& t : r.writes) topics[t].first.emplace_back(r.name);
    for (const std::string& t : r.reads) topics[t].second.emplace_back(r.name);
  }
  std::fprintf(out, "\ntopics (writer -> readers):\n");
  for (const auto& [name, ends] : topics)
    std::fprintf(out, "  %-20s %s -> %s\n", name.c_str(), joined(ends.first).c_str(), joined(ends.second).c_str());
  bool any_absent = false;
  for (const RowWiring& r : rows) any_absent = any_absent || !r.absent.empty();
  if (any_absent) {
    std::fprintf(out, "\nrows this configuration does not run:\n");
    for (const RowWiring& r : rows)
      if (!r.absent.empty())
        std::fprintf(out, "  %-12.*s %s\n", static_cast<int>(r.name.size()), r.name.data(), r.absent.c_str());
  }
}

void print_graph_mermaid(std::span<const RowWiring> rows, std::FILE* out) {
  std::fprintf(out, "flowchart LR\n");
  for (const RowWiring& r : rows) {
    if (!r.absent.empty()) continue;
    const int n = static_cast<int>(r.name.size());
    std::fprintf(out, "  %.*s[\"%.*s\"]\n", n, r.name.data(), n, r.name.data());
    // The outside world: one node per line of what comes in and what goes out.
    for (std::size_t i = 0; i < r.devices.size(); ++i) {
      const std::string& d = r.devices[i];
      std::string label = d.substr(3, d.find(" (") == std::string::npos ? std::string::npos : d.find(" (") - 3);
      std::replace(label.begin(), label.end(), '"', '\'');
      if (d.starts_with("<-"))
        std::fprintf(out, "  %.*s_d%zu((\"%s\")) --> %.*s\n", n, r.name.data(), i, label.c_str(), n, r.name.data());
      else
        std::fprintf(out, "  %.*s --> %.*s_d%zu((\"%s\"))\n", n, r.name.data(), n, r.name.data(), i, label.c_str());
    }
  }
  std::vector<std::string> topics;
  for (const RowWiring& r : rows)
    for (const auto* list : {&r.reads, &r.writes})
      for (const std::string& t : *list)
        if (std::find(topics.begin(), topics.end(), t) == topics.end()) topics.push_back(t);
  std::sort(topics.begin(), topics.end());
  for (const std::string& t : topics) std::fprintf(out, "  t_%s[/\"%s\"/]\n", t.c_str(), t.c_str());
  for (const RowWiring& r : rows) {
    const int n = static_cast<int>(r.name.size());
    for (const std::string& t : r.writes) std::fprintf(out, "  %.*s --> t_%s\n", n, r.name.data(), t.c_str());
    for (const std::string& t : r.reads) std::fprintf(out, "  t_%s --> %.*s\n", t.c_str(), n, r.name.data());
    for (const std::string& u : r.uses) std::fprintf(out, "  %s -.-> %.*s\n", u.c_str(), n, r.name.data());
  }
}

}  // namespace sen3bot::firmware
