#include <algorithm>
#include <tessera/online/absorb_gate.hpp>

namespace tessera {

const Watermarks& AbsorbGate::decide(const std::vector<Watermarks>& reports) {
  if (reports.empty()) return entered_;
  // Robots named by any report; a report that does not name one holds none of its batches.
  Watermarks common;
  for (const auto& report : reports)
    for (const auto& [robot, count] : report) common.emplace(robot, count);
  for (auto& [robot, count] : common)
    for (const auto& report : reports) {
      auto it = report.find(robot);
      count = std::min(count, it == report.end() ? std::uint64_t{0} : it->second);
    }
  // Never go back: a late report (an agent that restarted) cannot take data out again.
  for (const auto& [robot, count] : common)
    if (count > entered(robot)) entered_[robot] = count;
  return entered_;
}

std::uint64_t AbsorbGate::entered(std::uint32_t robot) const {
  auto it = entered_.find(robot);
  return it == entered_.end() ? 0 : it->second;
}

}  // namespace tessera
