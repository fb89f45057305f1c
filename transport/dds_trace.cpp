#include "transport/dds_trace.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>

namespace tessera::transport {

DdsTrace::DdsTrace(std::string who) : who_(std::move(who)) {
  if (const char* env = std::getenv("TESSERA_DDS_TRACE"); env && *env && *env != '0') on_ = true;
}

void DdsTrace::operator()(const char* fmt, ...) const {
  if (!on_) return;
  char text[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(text, sizeof(text), fmt, args);
  va_end(args);
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "[dds %8.3f %s] %s\n", t, who_.c_str(), text);
}

}  // namespace tessera::transport
