#include <tessera/distributed/round_history.hpp>
#include <utility>

namespace tessera {

void RoundHistory::push_back(RoundRecord record) {
  if (tail_.size() == kChunk) {
    sealed_.push_back(std::make_shared<const std::vector<RoundRecord>>(std::move(tail_)));
    tail_.clear();  // (a moved-from vector is valid but unspecified)
  }
  tail_.push_back(std::move(record));
}

std::vector<RoundRecord> RoundHistory::to_vector() const {
  std::vector<RoundRecord> out;
  out.reserve(size());
  for (const auto& chunk : sealed_) out.insert(out.end(), chunk->begin(), chunk->end());
  out.insert(out.end(), tail_.begin(), tail_.end());
  return out;
}

}  // namespace tessera
