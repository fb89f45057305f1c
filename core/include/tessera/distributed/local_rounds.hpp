#pragma once
// Local rounds: when a few blocks got new data (an online run's new measurements), the rest of
// the iterate is already converged and only the blocks near the change need work. A block is
// active in a round when its own gradient norm is above threshold * grad_norm_tol / sqrt(N):
// then, if every block is inactive, ||grad f||^2 = sum of the blocks' squares <= grad_norm_tol^2
// and the global stop holds, and while it does not hold at least one block is active (with
// threshold <= 1), so the rule never stalls a run that has work left. Only active blocks can be
// selected and take their momentum step; an inactive block keeps Y, sets V := Y (its momentum
// restarts when it wakes up) and computes nothing.
//
// A block's round status depends only on its own poses and its copies of its neighbours'
// public poses, so it changes only when the block or a neighbour moved in the last round
// (selected, or an active block taking its extrapolated point). Every agent knows who moved
// (the selection and the activity follow from the statuses every agent has), so only those
// blocks send a status; the others' last statuses stand for them, bit for bit. A converged
// block whose neighbours do not move therefore sends nothing, computes nothing and is never
// factored again. The stop rule stays global: the sum over every block's latest status.

#include <cstdint>
#include <tessera/distributed/block_layout.hpp>
#include <vector>

namespace tessera {

struct LocalRoundOptions {
  /// Off: every block sends its status and takes its momentum step in every round (the batch
  /// solvers' rounds).
  bool enabled = false;
  /// A block is active while ||grad_B f|| > threshold * grad_norm_tol / sqrt(N); in (0, 1]
  /// (above 1 a run could stop updating with the global gradient still above the tolerance).
  double threshold = 1.0;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// One agent's view of every block's latest status and of who moved, identical on all agents.
class LocalRounds {
 public:
  /// `grad_norm_tol`: the solve's gradient tolerance (the activity bound scales with it).
  LocalRounds(const BlockLayout& layout, const LocalRoundOptions& options, double grad_norm_tol);

  /// The blocks that send a status this round, ascending: every block at the first status of
  /// a solve; afterwards the blocks that moved in the last round and their neighbours.
  std::vector<int> status_senders() const;
  bool sends_status(int block) const;
  /// A block's status at this round (the senders' only).
  void record(int block, double cost, double grad_norm_sq, double score);
  /// Sums of every block's latest cost and squared gradient norm, in block-id order (the same
  /// on every agent).
  double cost() const;
  double grad_norm_sq() const;
  /// Selection scores: the latest score of active blocks, 0 for inactive ones.
  std::vector<double> scores() const;
  bool active(int block) const { return active_[static_cast<std::size_t>(block)] != 0; }
  /// Updates the activity from the latest statuses (after the round's statuses are recorded).
  void update_activity();
  /// The blocks that move in this round (their status, and their neighbours', change).
  void set_moved(const std::vector<int>& blocks);
  bool moved(int block) const { return moved_[static_cast<std::size_t>(block)] != 0; }
  /// The activity bound threshold * grad_norm_tol / sqrt(N).
  double bound() const { return bound_; }

 private:
  const BlockLayout& layout_;
  double bound_;
  bool first_ = true;  // no status recorded yet: everyone sends
  std::vector<double> cost_, gsq_, score_;
  std::vector<char> active_, moved_;
};

}  // namespace tessera
