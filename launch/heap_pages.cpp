#include "launch/heap_pages.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <tessera/util/input_error.hpp>
#include <vector>

namespace tessera::launch {

namespace {

// The choice as this process (or its parent) recorded it: "<4k|2m> <us> <reason>".
constexpr const char* kRecordVariable = "TESSERA_HEAP_PAGES";
constexpr const char* kTunable = "glibc.malloc.hugetlb";

std::string env_or_empty(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

// The value GLIBC_TUNABLES gives glibc.malloc.hugetlb ("" when it gives none).
std::string hugetlb_value(const std::string& tunables) {
  std::stringstream in(tunables);
  std::string item;
  std::string value;
  while (std::getline(in, item, ':'))  // the last setting wins, as in glibc
    if (item.rfind(std::string(kTunable) + "=", 0) == 0)
      value = item.substr(std::strlen(kTunable) + 1);
  return value;
}

bool hugetlb_on(const std::string& tunables) {
  const std::string v = hugetlb_value(tunables);
  return !v.empty() && v != "0";
}

// GLIBC_TUNABLES with glibc.malloc.hugetlb set to `value` and every other setting kept.
std::string with_hugetlb(const std::string& tunables, const char* value) {
  std::stringstream in(tunables);
  std::string item;
  std::string out;
  while (std::getline(in, item, ':')) {
    if (item.empty() || item.rfind(std::string(kTunable) + "=", 0) == 0) continue;
    out += item + ":";
  }
  return out + kTunable + "=" + value;
}

std::string read_thp_setting() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string text;
  std::getline(in, text);
  return text;
}

std::string format_us(double us) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", us);
  return buf;
}

void record(const HeapPagesChoice& c) {
  const std::string text = c.name() + " " + format_us(c.fresh_page_us) + " " + c.reason;
  setenv(kRecordVariable, text.c_str(), 1);
}

bool parse_record(const std::string& text, HeapPagesChoice& out) {
  std::stringstream in(text);
  std::string name;
  double us = -1;
  if (!(in >> name >> us) || (name != "4k" && name != "2m")) return false;
  out.huge = name == "2m";
  out.fresh_page_us = us;
  std::getline(in >> std::ws, out.reason);
  return true;
}

// The choice recorded in the environment, when it is the one in effect (GLIBC_TUNABLES agrees).
std::optional<HeapPagesChoice> recorded_choice() {
  HeapPagesChoice c;
  if (parse_record(env_or_empty(kRecordVariable), c) &&
      c.huge == hugetlb_on(env_or_empty("GLIBC_TUNABLES")))
    return c;
  return std::nullopt;
}

// This process's own command line, from /proc (what main() was given), for execv.
std::vector<std::string> own_command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> args;
  for (std::string arg; std::getline(in, arg, '\0');) args.push_back(arg);
  return args;
}

}  // namespace

HeapPages parse_heap_pages(const std::string& value, const std::string& flag) {
  if (value == "auto") return HeapPages::kAuto;
  if (value == "4k") return HeapPages::kSmall;
  if (value == "2m") return HeapPages::kHuge;
  throw InputError(flag + " must be auto, 4k or 2m, not '" + value + "'");
}

HeapPagesChoice decide_heap_pages(HeapPages mode, const std::string& tunables,
                                  const std::string& thp, double (*probe)()) {
  HeapPagesChoice c;
  const bool thp_off = thp.find("[never]") != std::string::npos;
  if (mode == HeapPages::kSmall) {
    c.reason = "--heap-pages 4k";
    return c;
  }
  if (mode == HeapPages::kHuge) {
    c.huge = !thp_off;
    c.reason = thp_off ? "--heap-pages 2m, but transparent huge pages are off on this host"
                       : "--heap-pages 2m";
    return c;
  }
  const std::string user = hugetlb_value(tunables);
  if (!user.empty()) {
    c.huge = hugetlb_on(tunables);
    c.reason = "GLIBC_TUNABLES sets " + std::string(kTunable) + "=" + user;
    return c;
  }
  if (thp_off) {
    c.reason = "transparent huge pages are off on this host";
    return c;
  }
  c.fresh_page_us = probe();
  c.huge = c.fresh_page_us >= kHugeFromFreshPageUs;
  c.reason = "a fresh 4 KB page costs " + format_us(c.fresh_page_us) +
             " us here (2 MB pages from " + format_us(kHugeFromFreshPageUs) + ")";
  return c;
}

double fresh_page_cost_us() {
  constexpr std::size_t kPage = 4096, kBatch = 32, kBatches = 4;
  const std::size_t bytes = kPage * kBatch * kBatches;
  void* mapped = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (mapped == MAP_FAILED) return -1;
  // 4 KB pages whatever the host's THP mode, so the probe measures what it names.
  madvise(mapped, bytes, MADV_NOHUGEPAGE);
  auto* p = static_cast<volatile char*>(mapped);
  double best = 1e300;
  for (std::size_t b = 0; b < kBatches; ++b) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t k = 0; k < kBatch; ++k) p[(b * kBatch + k) * kPage] = 1;
    const std::chrono::duration<double, std::micro> took = std::chrono::steady_clock::now() - t0;
    best = std::min(best, took.count() / kBatch);
  }
  munmap(mapped, bytes);
  return best;
}

HeapPagesChoice enter_heap_pages(HeapPages mode) {
  // A parent (or this process before it re-executed) has decided already.
  if (mode == HeapPages::kAuto)
    if (std::optional<HeapPagesChoice> recorded = recorded_choice()) return *recorded;
  const std::string tunables = env_or_empty("GLIBC_TUNABLES");
  HeapPagesChoice c = decide_heap_pages(mode, tunables, read_thp_setting(), &fresh_page_cost_us);
  if (c.huge != hugetlb_on(tunables)) {
    // glibc reads its tunables once, at start-up: only a new image of this process takes them.
    const std::string next = with_hugetlb(tunables, c.huge ? "1" : "0");
    record(c);
    setenv("GLIBC_TUNABLES", next.c_str(), 1);
    std::vector<std::string> args = own_command_line();
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv("/proc/self/exe", argv.data());
    const int err = errno;
    if (tunables.empty())
      unsetenv("GLIBC_TUNABLES");
    else
      setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
    c.reason += std::string(", but re-executing failed (") + std::strerror(err) + ")";
    c.huge = hugetlb_on(tunables);
  }
  record(c);
  return c;
}

HeapPagesChoice heap_pages_in_effect() {
  if (std::optional<HeapPagesChoice> recorded = recorded_choice()) return *recorded;
  const std::string tunables = env_or_empty("GLIBC_TUNABLES");
  HeapPagesChoice c;
  c.huge = hugetlb_on(tunables);
  c.reason = hugetlb_value(tunables).empty()
                 ? "glibc's default"
                 : "GLIBC_TUNABLES sets " + std::string(kTunable) + "=" + hugetlb_value(tunables);
  return c;
}

}  // namespace tessera::launch
