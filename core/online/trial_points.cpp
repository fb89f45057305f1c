#include "online/trial_points.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/problem/lifting.hpp>
#include <utility>

namespace tessera {

TrialPoints::TrialPoints(int blocks, std::function<double()> wall_s, std::function<double()> cpu_s,
                         std::function<long long(int)> factorizations, long long earlier)
    : blocks_(blocks),
      wall_s_(std::move(wall_s)),
      cpu_s_(std::move(cpu_s)),
      factorizations_(std::move(factorizations)),
      earlier_(earlier),
      calls_(static_cast<std::size_t>(blocks), 0) {
  for (int b = 0; b < blocks_; ++b) factorizations_before_.push_back(factorizations_(b));
}

TrialPointWatch TrialPoints::watch() {
  return [this](int b, const Eigen::MatrixXd& Y) {
    const double wall = wall_s_(), cpu = cpu_s_();
    // This block's own count, on its own thread: no other thread changes it meanwhile.
    const long long factored =
        factorizations_(b) - factorizations_before_[static_cast<std::size_t>(b)];
    const std::lock_guard<std::mutex> lock(mutex_);
    const std::size_t k = calls_[static_cast<std::size_t>(b)]++;
    if (trials_.size() <= k) trials_.resize(k + 1);
    Trial& t = trials_[k];
    if (t.blocks.empty()) t.blocks.resize(static_cast<std::size_t>(blocks_));
    t.blocks[static_cast<std::size_t>(b)] = Y;
    t.wall_s = std::max(t.wall_s, wall);
    t.cpu_s = std::max(t.cpu_s, cpu);
    t.factorizations += factored;
    ++t.received;
  };
}

void TrialPoints::accepted(const std::vector<NewtonRefineResult>& refines, const LiveBlocks& blocks,
                           const Eigen::MatrixXd& X, std::vector<StepPoint>& out) const {
  std::vector<const NewtonRefineStep*> steps;
  for (const NewtonRefineResult& r : refines)
    for (const NewtonRefineStep& s : r.trace) steps.push_back(&s);
  if (steps.size() != trials_.size())
    throw std::logic_error("online step points: " + std::to_string(trials_.size()) +
                           " trial points for " + std::to_string(steps.size()) + " Newton steps");
  const BlockLayout& layout = blocks.layout();
  const int d = blocks.graph().d;
  int cg = 0;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    cg += steps[k]->cg_iterations;
    if (!steps[k]->accepted) continue;
    const Trial& t = trials_[k];
    if (t.received != blocks_)
      throw std::logic_error("online step points: a trial point lacks a block");
    // Every linked pose is in one block, so every column is written.
    Eigen::MatrixXd linked(X.rows(), (d + 1) * static_cast<Eigen::Index>(layout.owner.size()));
    for (int b = 0; b < blocks_; ++b)
      scatter_pose_columns(t.blocks[static_cast<std::size_t>(b)],
                           layout.poses[static_cast<std::size_t>(b)], d, linked);
    StepPoint p{
        {"newton", t.wall_s, t.cpu_s, static_cast<int>(k) + 1, cg, earlier_ + t.factorizations}, X};
    blocks.write_back(linked, p.X);
    out.push_back(std::move(p));
  }
}

}  // namespace tessera
