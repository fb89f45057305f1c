#pragma once
// The online input topic "tessera_graph_stream" (docs/online.md): robots' front ends (or
// `tessera replay`) write wire::GraphStreamBatch samples keyed by robot; agents read them.
// Reliable and TRANSIENT_LOCAL with the whole history kept, so a reader that starts after the
// writer (an agent that joins late, or agents started after the replay) still receives every
// batch from the first: a mission's graph must arrive whole, whenever its solver starts. Its
// own small participant (not a Session): a front end is not part of any run's hand-shake.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <tessera/online/stream_batch.hpp>
#include <vector>

namespace tessera::transport {

inline constexpr const char* kGraphStreamTopic = "tessera_graph_stream";

/// A batch as received, with the fields the core type does not carry.
struct ReceivedStreamBatch {
  StreamBatch batch;
  int dim = 0;
  bool last = false;  ///< The robot publishes nothing after it.
};

class GraphStreamWriter {
 public:
  /// Joins DDS domain `domain` with partition `run_id` (validated: InputError). Throws
  /// std::runtime_error when DDS refuses.
  GraphStreamWriter(int domain, const std::string& run_id);
  ~GraphStreamWriter();
  GraphStreamWriter(const GraphStreamWriter&) = delete;
  GraphStreamWriter& operator=(const GraphStreamWriter&) = delete;

  /// Writes one batch (`d` = its dimension). Throws std::runtime_error when the write fails.
  void publish(const StreamBatch& batch, int d, bool last);
  /// Readers currently matched.
  int matched_readers() const;
  /// Waits until every matched reader acknowledged all samples, at most `timeout_s`.
  bool wait_acknowledged(double timeout_s);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class GraphStreamReader {
 public:
  /// `robot`: only that robot's batches (an agent's own stream); nullopt = every robot.
  GraphStreamReader(int domain, const std::string& run_id,
                    std::optional<std::uint32_t> robot = std::nullopt);
  ~GraphStreamReader();
  GraphStreamReader(const GraphStreamReader&) = delete;
  GraphStreamReader& operator=(const GraphStreamReader&) = delete;

  /// Waits up to `timeout_s` for data (returns at once when some is there), then takes every
  /// batch received so far, in arrival order. Throws InputError for a malformed sample.
  std::vector<ReceivedStreamBatch> take(double timeout_s);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tessera::transport
