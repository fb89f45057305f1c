#pragma once
// The rounds of one agent's protocol run so far (its trace), as a value that is cheap to copy:
// a fault-tolerant run snapshots the protocol every round (protocol_snapshot.hpp), and a copy
// of a plain vector made that O(rounds) per round, O(rounds^2) over the run. Here records are
// kept in chunks of kChunk; a full chunk is never changed again and copies share it, so a copy
// costs rounds / kChunk pointer copies plus at most kChunk records. Copies are independent
// values (changing one never shows in another) and may be read from different threads.

#include <cstddef>
#include <memory>
#include <vector>

namespace tessera {

/// One round as every agent sees it (identical on all agents).
struct RoundRecord {
  int round = 0;
  double cost = 0.0;       ///< f(Y^k), full sum.
  double grad_norm = 0.0;  ///< ||grad f(Y^k)||.
  std::vector<int> selected;
  bool restart = false;    ///< The update of this round was redone from Y^k.
  double elapsed_s = 0.0;  ///< Since start(), when the status completed (not part of the iterates).
};

class RoundHistory {
 public:
  static constexpr std::size_t kChunk = 32;

  std::size_t size() const { return sealed_.size() * kChunk + tail_.size(); }
  bool empty() const { return tail_.empty(); }
  /// Record i, 0 <= i < size().
  const RoundRecord& operator[](std::size_t i) const {
    const std::size_t chunk = i / kChunk;
    return chunk < sealed_.size() ? (*sealed_[chunk])[i % kChunk]
                                  : tail_[i - sealed_.size() * kChunk];
  }
  /// The last record (not empty()). Only it can be changed (a round's restart flag is set
  /// after its record was added).
  const RoundRecord& back() const { return tail_.back(); }
  RoundRecord& back() { return tail_.back(); }
  void push_back(RoundRecord record);
  /// Every record in order.
  std::vector<RoundRecord> to_vector() const;

 private:
  // Full chunks, shared by copies; tail_ holds the rest, 1..kChunk records once not empty (a
  // chunk is sealed only when a record follows it, so back() is always in tail_).
  std::vector<std::shared_ptr<const std::vector<RoundRecord>>> sealed_;
  std::vector<RoundRecord> tail_;
};

}  // namespace tessera
