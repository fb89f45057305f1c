#include "runtime/checkpoint_keeper.hpp"

#include <algorithm>
#include <tessera/distributed/checkpoint_file.hpp>
#include <tessera/util/input_error.hpp>

#include "runtime/agent_checkpoint.hpp"

namespace tessera::agent {

void CheckpointOptions::validate() const {
  if (every < 1 || every > 1000000)
    throw InputError("option --checkpoint-every: must be 1..1000000, got " + std::to_string(every));
}

bool snapshots_needed(const SnapshotReaders& r) {
  return r.rejoin || r.restarted || r.checkpoint_files || r.replicas;
}

CheckpointKeeper::CheckpointKeeper(std::string run_id, const AgentLocalData& local,
                                   CheckpointOptions options)
    : run_id_(std::move(run_id)), local_(local), opt_(std::move(options)) {
  opt_.validate();
  // A rollback goes to a round of the restarted agent's file, which is at most two
  // checkpoint intervals (plus the rounds a survivor can run ahead) behind any survivor.
  keep_ = static_cast<std::size_t>(2 * opt_.every + 4);
}

std::string CheckpointKeeper::path() const {
  return checkpoint_path(opt_.dir, local_.agent_id);
}

void CheckpointKeeper::adopt(const std::vector<ProtocolSnapshot>& from_file) {
  in_file_ = from_file;
  for (const auto& s : from_file) memory_.push_back(s);
}

void CheckpointKeeper::on_round(const ProtocolSnapshot& s) {
  while (!memory_.empty() && memory_.back().round >= s.round) memory_.pop_back();
  memory_.push_back(s);
  while (memory_.size() > keep_) memory_.pop_front();
  if (opt_.dir.empty() || s.round % opt_.every != 0) return;
  while (!in_file_.empty() && in_file_.back().round >= s.round) in_file_.pop_back();
  in_file_.push_back(s);
  if (in_file_.size() > 2) in_file_.erase(in_file_.begin());
  write_file();
}

void CheckpointKeeper::write_file() {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string payload = encode_checkpoint(run_id_, local_, in_file_);
  write_checkpoint_file(path(), payload);
  stats_.write_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++stats_.writes;
  stats_.last_bytes = payload.size();
  stats_.last_round = in_file_.back().round;
}

const ProtocolSnapshot* CheckpointKeeper::find(int round) const {
  for (const auto& s : memory_)
    if (s.round == round) return &s;
  return nullptr;
}

std::string CheckpointKeeper::held_rounds() const {
  if (memory_.empty()) return "none";
  return std::to_string(memory_.front().round) + ".." + std::to_string(memory_.back().round);
}

}  // namespace tessera::agent
