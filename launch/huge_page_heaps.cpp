#include "launch/huge_page_heaps.hpp"

#include <algorithm>
#include <cstdlib>

namespace tessera::launch {

namespace {
constexpr const char* kHugeTlb = "glibc.malloc.hugetlb";
}  // namespace

std::string with_huge_page_heaps(const std::string& tunables) {
  // GLIBC_TUNABLES is a colon-separated list of name=value.
  for (std::size_t at = 0; at <= tunables.size();) {
    const std::size_t end = std::min(tunables.find(':', at), tunables.size());
    const std::string item = tunables.substr(at, end - at);
    if (item.compare(0, item.find('='), kHugeTlb) == 0) return tunables;
    at = end + 1;
  }
  const std::string mine = std::string(kHugeTlb) + "=1";
  return tunables.empty() ? mine : tunables + ":" + mine;
}

void request_huge_page_heaps() {
  const char* now = std::getenv("GLIBC_TUNABLES");
  setenv("GLIBC_TUNABLES", with_huge_page_heaps(now ? now : "").c_str(), 1);
}

}  // namespace tessera::launch
