#pragma once
// Network namespaces as stand-in hosts for the DDS tests (header-only): K hosts made by
// scripts/netns/netns.sh with a test's own prefix and 10.77.X subnet, always removed when
// the object goes, commands run inside host k, and frame loss on one host's link.

#include <unistd.h>

#include <string>
#include <vector>

#include "test_support.hpp"

namespace tessera::test::dds {

inline std::string netns_script() {
  return std::string(TESSERA_SOURCE_DIR) + "/scripts/netns/netns.sh";
}

/// Whether this process can make namespaces; `why` says why not (for GTEST_SKIP).
inline bool namespaces_available(std::string* why) {
  if (geteuid() != 0) {
    *why = "not root";
    return false;
  }
  std::string out;
  if (run_command(netns_script() + " check", &out) != 0) {
    *why = out;
    return false;
  }
  return true;
}

class NetnsHosts {
 public:
  /// Hosts `prefix`-0 .. -(count-1) with addresses `subnet`.1 .. (e.g. subnet "10.77.30").
  NetnsHosts(const std::string& prefix, int count, const std::string& subnet)
      : prefix_(prefix), subnet_(subnet) {
    std::string out;
    ok_ =
        run_command(netns_script() + " up " + prefix_ + " " + std::to_string(count) + " " + subnet_,
                    &out) == 0;
    error_ = out;
  }
  ~NetnsHosts() { run_command(netns_script() + " down " + prefix_, nullptr); }
  NetnsHosts(const NetnsHosts&) = delete;
  NetnsHosts& operator=(const NetnsHosts&) = delete;

  bool ok() const { return ok_; }
  const std::string& error() const { return error_; }
  /// argv that runs `argv` inside host `host`.
  std::vector<std::string> in(int host, const std::vector<std::string>& argv) const {
    std::vector<std::string> a = {"/usr/bin/env", "ip", "netns", "exec",
                                  prefix_ + "-" + std::to_string(host)};
    a.insert(a.end(), argv.begin(), argv.end());
    return a;
  }
  std::string address(int host) const { return subnet_ + "." + std::to_string(host + 1); }
  /// Drops `percent`% of the frames on host `host`'s link, both ways (0 removes it).
  bool set_loss(int host, int percent) const {
    return run_command(netns_script() + " loss " + prefix_ + " " + std::to_string(host) + " " +
                           std::to_string(percent),
                       nullptr) == 0;
  }
  /// Frames dropped so far on host `host`'s link (both directions), -1 if unknown.
  long dropped_frames(int host) const {
    long total = 0;
    bool any = false;
    for (const std::string& ns : {prefix_ + "-" + std::to_string(host), prefix_ + "-br"}) {
      std::string out;
      if (run_command("ip netns exec " + ns + " nft list table netdev tessera_loss", &out) != 0)
        continue;
      const auto at = out.find("counter packets ");
      if (at == std::string::npos) continue;
      total += std::stol(out.substr(at + 16));
      any = true;
    }
    return any ? total : -1;
  }

 private:
  std::string prefix_, subnet_, error_;
  bool ok_ = false;
};

}  // namespace tessera::test::dds
