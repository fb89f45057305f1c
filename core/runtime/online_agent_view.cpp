#include "runtime/online_agent_view.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/online/estimate_extension.hpp>
#include <tessera/online/new_pose_placement.hpp>
#include <tessera/util/input_error.hpp>
#include <tuple>

#include "runtime/online_takeover.hpp"

namespace tessera::runtime {

OnlineAgentView::OnlineAgentView(int agent, int robots, const OnlineOptions& options)
    : agent_(agent), robots_(robots), options_(options) {
  options_.validate();
  if (robots < 1) throw InputError("online agent: robots must be >= 1");
  if (agent < 0 || agent >= robots)
    throw InputError("online agent: agent id " + std::to_string(agent) + " is not in 0.." +
                     std::to_string(robots - 1));
}

void OnlineAgentView::receive(const StreamBatch& batch, int dim, bool last) {
  const std::string where =
      "robot " + std::to_string(batch.robot) + " batch " + std::to_string(batch.sequence);
  if (batch.robot >= static_cast<std::uint32_t>(robots_))
    throw InputError("graph stream: " + where + ": robot is not one of the run's " +
                     std::to_string(robots_) + " robots (0.." + std::to_string(robots_ - 1) + ")");
  if (d_ == 0) {
    if (dim != 2 && dim != 3) throw InputError("graph stream: " + where + ": dim must be 2 or 3");
    if (options_.solver.rank < dim)
      throw InputError("online agent: rank " + std::to_string(options_.solver.rank) +
                       " is below d = " + std::to_string(dim));
    d_ = dim;
    stream_.emplace(dim, "graph stream");
    X_.resize(options_.solver.rank, 0);
  } else if (dim != d_) {
    throw InputError("graph stream: " + where + ": dim " + std::to_string(dim) +
                     " differs from the stream's " + std::to_string(d_));
  }
  if (last) last_count_[batch.robot] = batch.sequence + 1;
  if (batch.sequence >= stream_->absorbed_batches(batch.robot))
    pending_[batch.robot].emplace(batch.sequence, batch);
}

Watermarks OnlineAgentView::held() const {
  Watermarks out;
  if (!stream_) return out;
  for (const auto& [robot, batches] : pending_) {
    std::uint64_t next = stream_->absorbed_batches(robot);
    for (auto it = batches.find(next); it != batches.end() && it->first == next; ++it) ++next;
    out[robot] = next;
  }
  for (std::uint32_t robot : stream_->robots())
    out.emplace(robot, stream_->absorbed_batches(robot));
  return out;
}

EnteredData OnlineAgentView::enter(const Watermarks& decision) {
  EnteredData e;
  if (!stream_) return e;
  std::vector<StreamBatch> in;
  for (auto& [robot, batches] : pending_) {
    auto limit = decision.find(robot);
    const std::uint64_t until = limit == decision.end() ? 0 : limit->second;
    for (auto it = batches.begin(); it != batches.end() && it->first < until;) {
      in.push_back(std::move(it->second));
      it = batches.erase(it);
    }
  }
  if (in.empty()) return e;
  // One order on every agent: graph ids follow absorption.
  std::sort(in.begin(), in.end(), [](const StreamBatch& a, const StreamBatch& b) {
    return std::tie(a.stamp, a.robot, a.sequence) < std::tie(b.stamp, b.robot, b.sequence);
  });
  const std::size_t poses_before = stream_->graph().num_poses;
  const std::size_t measurements_before = stream_->graph().measurements.size();
  for (const StreamBatch& b : in) {
    e.batches += stream_->absorb(b).batches;
    e.stamps.push_back(b.stamp);
  }
  const PoseGraph& graph = stream_->graph();
  e.poses = graph.num_poses - poses_before;
  e.measurements = graph.measurements.size() - measurements_before;
  const auto& robots = stream_->robots();
  const std::size_t first_new = owner_.size();
  assign_new_poses(graph, owner_, stream_->robot_blocks_from(first_new), options_.rebalance);
  RebalanceResult moves;
  if (lost_.empty()) {
    moves = rebalance_blocks(graph, owner_, static_cast<int>(robots.size()), options_.rebalance);
  } else {
    adopt_lost_poses(first_new);
    moves = rebalance_live_blocks();
  }
  e.moved = moves.moved;
  e.largest_block = moves.largest_after;
  e.smallest_block = moves.smallest_after;
  e.cut = moves.cut_after;
  const std::size_t estimated = static_cast<std::size_t>(X_.cols()) / (graph.d + 1);
  EstimateExtension x = extend_estimate(graph, X_, stream_->guesses());
  X_ = std::move(x.X);
  if (options_.place_new_poses) place_new_poses(graph, X_, estimated, measurements_before);
  e.composed = x.composed;
  e.merges = pieces_.absorb(graph, X_, options_.align_merged_pieces).merges;
  return e;
}

bool OnlineAgentView::is_lost_block(int b) const {
  return lost_.count(stream_->robots()[static_cast<std::size_t>(b)]) > 0;
}

void OnlineAgentView::adopt_lost_poses(std::size_t first_new) {
  // A lost robot's new poses join the block that adopted it; a robot lost before its first
  // pose is adopted by the smallest live block (lowest on ties) when that pose enters.
  const auto& robots = stream_->robots();
  for (std::size_t k = first_new; k < owner_.size(); ++k) {
    const std::uint32_t robot = robots[static_cast<std::size_t>(owner_[k])];
    if (lost_.count(robot) == 0) continue;
    int& adopter = adopter_[robot];
    if (adopter < 0) {
      std::vector<std::size_t> size(robots.size(), 0);
      for (int b : owner_) ++size[static_cast<std::size_t>(b)];
      for (int b = 0; b < static_cast<int>(robots.size()); ++b)
        if (!is_lost_block(b) && (adopter < 0 || size[static_cast<std::size_t>(b)] <
                                                     size[static_cast<std::size_t>(adopter)]))
          adopter = b;
      if (adopter < 0)
        throw std::runtime_error("online agent: robot " + std::to_string(robot) +
                                 "'s agent was lost and no survivor's robot has a block yet");
    }
    owner_[k] = adopter;
  }
}

RebalanceResult OnlineAgentView::rebalance_live_blocks() {
  // The bound is over the live blocks: counting the lost (empty) ones would make every
  // survivor's block look over-full and move poses back and forth between them.
  const int blocks = static_cast<int>(stream_->robots().size());
  std::vector<int> dense(static_cast<std::size_t>(blocks), -1), block_of;
  for (int b = 0; b < blocks; ++b)
    if (!is_lost_block(b)) {
      dense[static_cast<std::size_t>(b)] = static_cast<int>(block_of.size());
      block_of.push_back(b);
    }
  std::vector<int> owner(owner_.size());
  for (std::size_t k = 0; k < owner_.size(); ++k)
    owner[k] = dense[static_cast<std::size_t>(owner_[k])];
  const RebalanceResult r = rebalance_blocks(stream_->graph(), owner,
                                             static_cast<int>(block_of.size()), options_.rebalance);
  for (std::size_t k = 0; k < owner_.size(); ++k)
    owner_[k] = block_of[static_cast<std::size_t>(owner[k])];
  return r;
}

int OnlineAgentView::adopter(std::uint32_t robot) const {
  auto it = adopter_.find(robot);
  return it == adopter_.end() ? -1 : it->second;
}

Watermarks OnlineAgentView::entered() const {
  Watermarks out;
  if (!stream_) return out;
  for (std::uint32_t robot : stream_->robots()) out[robot] = stream_->absorbed_batches(robot);
  return out;
}

TakeoverMoves OnlineAgentView::take_over(const std::set<std::uint32_t>& lost) {
  lost_.insert(lost.begin(), lost.end());
  TakeoverMoves out;
  if (!stream_) {
    for (std::uint32_t r : lost_) adopter_.emplace(r, -1);
    return out;
  }
  SurvivorRepartitionOptions options;
  options.eps = std::min(1.0, options_.rebalance.slack);
  const OnlineTakeoverPlan plan =
      plan_online_takeover(stream_->graph(), owner_, stream_->robots(), lost_, options);
  owner_ = plan.owner;
  // A robot adopted earlier by a block lost now follows that block's poses.
  for (std::uint32_t robot : lost_) {
    int a = adopter(robot);
    if (a < 0 || is_lost_block(a)) {
      const int fresh = plan.adopter.at(robot);
      a = fresh >= 0 ? fresh
          : a >= 0   ? plan.adopter.at(stream_->robots()[static_cast<std::size_t>(a)])
                     : -1;
    }
    adopter_[robot] = a;
  }
  out.moved = plan.moved;
  out.cut_after = plan.cut_after;
  return out;
}

bool OnlineAgentView::stream_over() const {
  if (!stream_) return false;
  for (int r = 0; r < robots_; ++r) {
    auto it = last_count_.find(static_cast<std::uint32_t>(r));
    if (it == last_count_.end() ||
        stream_->absorbed_batches(static_cast<std::uint32_t>(r)) < it->second)
      return false;
  }
  return true;
}

void OnlineAgentView::apply_block(const std::vector<std::uint32_t>& ids,
                                  const std::vector<double>& data, int rank) {
  if (d_ == 0 || ids.empty()) return;
  const Eigen::Index w = d_ + 1;
  if (rank > X_.rows()) {
    Eigen::MatrixXd wider = Eigen::MatrixXd::Zero(rank, X_.cols());
    wider.topRows(X_.rows()) = X_;
    X_ = std::move(wider);
  }
  const std::size_t per_pose = static_cast<std::size_t>(rank * w);
  if (data.size() != ids.size() * per_pose)
    throw InputError("online report: " + std::to_string(data.size()) + " values for " +
                     std::to_string(ids.size()) + " poses of rank " + std::to_string(rank));
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (static_cast<Eigen::Index>(ids[k]) * w >= X_.cols())
      throw InputError("online report: pose " + std::to_string(ids[k]) + " is not in the graph");
    auto cols = X_.middleCols(w * static_cast<Eigen::Index>(ids[k]), w);
    cols.setZero();
    cols.topRows(rank) = Eigen::Map<const Eigen::MatrixXd>(data.data() + k * per_pose, rank, w);
  }
}

LinkedProblem OnlineAgentView::problem() const {
  return make_linked_problem(stream_->graph(), owner_, X_);
}

int OnlineAgentView::own_block() const {
  if (!stream_) return -1;
  const auto& robots = stream_->robots();
  auto it = std::find(robots.begin(), robots.end(), static_cast<std::uint32_t>(agent_));
  return it == robots.end() ? -1 : static_cast<int>(it - robots.begin());
}

}  // namespace tessera::runtime
