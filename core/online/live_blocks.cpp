#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/online/live_blocks.hpp>
#include <tessera/problem/lifting.hpp>

namespace tessera {

namespace {

constexpr std::size_t kNone = static_cast<std::size_t>(-1);

}  // namespace

LiveBlocks::LiveBlocks(int d, const BlockUpdateOptions& update, double refactor_growth,
                       int only_block)
    : d_(d),
      update_(update),
      refactor_growth_(refactor_growth),
      only_block_(only_block),
      layout_(std::make_unique<BlockLayout>()) {
  if (d != 2 && d != 3) throw std::invalid_argument("LiveBlocks: d must be 2 or 3");
  if (!(refactor_growth >= 0))
    throw std::invalid_argument("LiveBlocks: refactor_growth must be >= 0");
  graph_.d = d;
}

int LiveBlocks::compact_block(int b) const {
  return b >= 0 && static_cast<std::size_t>(b) < compact_block_of_.size()
             ? compact_block_of_[static_cast<std::size_t>(b)]
             : -1;
}

std::vector<AgentState*> LiveBlocks::all_states() const {
  std::vector<AgentState*> out;
  for (const auto& s : states_) {
    if (!s) throw std::logic_error("LiveBlocks::all_states: a block's state is not held");
    out.push_back(s.get());
  }
  return out;
}

void LiveBlocks::retire(const std::unique_ptr<AgentState>& state) {
  if (state)
    retired_ += {state->tangent_factorizations_total(), state->tangent_factor_flops_total()};
}

TangentFactorTotals LiveBlocks::tangent_factor_totals() const {
  TangentFactorTotals t = retired_;
  for (const auto& s : states_)
    if (s) t += {s->tangent_factorizations_total(), s->tangent_factor_flops_total()};
  return t;
}

Eigen::MatrixXd LiveBlocks::columns(const Eigen::MatrixXd& X,
                                    const std::vector<std::size_t>& compact) const {
  const Eigen::Index w = d_ + 1;
  Eigen::MatrixXd out(X.rows(), w * static_cast<Eigen::Index>(compact.size()));
  for (std::size_t s = 0; s < compact.size(); ++s)
    out.middleCols(w * static_cast<Eigen::Index>(s), w) =
        X.middleCols(w * static_cast<Eigen::Index>(full_id_[compact[s]]), w);
  return out;
}

void LiveBlocks::write_back(const Eigen::MatrixXd& Xc, Eigen::MatrixXd& X) const {
  const Eigen::Index w = d_ + 1;
  if (Xc.rows() != X.rows() || Xc.cols() != w * static_cast<Eigen::Index>(full_id_.size()))
    throw std::invalid_argument("LiveBlocks::write_back: iterate of the wrong size");
  scatter_pose_columns(Xc, full_id_, d_, X);
}

LiveSync LiveBlocks::sync(const PoseGraph& graph, const std::vector<int>& owner,
                          const Eigen::MatrixXd& X) {
  const Eigen::Index w = d_ + 1;
  if (graph.d != d_ || owner.size() != graph.num_poses || graph.num_poses < compact_of_.size() ||
      graph.measurements.size() < seen_measurements_ ||
      X.cols() != w * static_cast<Eigen::Index>(graph.num_poses))
    throw std::invalid_argument("LiveBlocks::sync: the graph, blocks or iterate do not fit");
  LiveSync out;
  compact_of_.resize(graph.num_poses, kNone);
  const std::size_t first_new = graph_.measurements.size();
  const std::size_t n_old = full_id_.size();
  // Poses a re-partition moved: the blocks that gave or took one are built again (growing them
  // in place would have to move rows between factors). The others keep their states: their own
  // poses and neighbour poses are the same, only the neighbours' owners changed.
  bool moved = false;
  std::vector<char> reshaped;  // by original block
  auto reshape = [&](int b) {
    if (b < 0) throw std::invalid_argument("LiveBlocks::sync: negative block");
    if (static_cast<std::size_t>(b) >= reshaped.size())
      reshaped.resize(static_cast<std::size_t>(b) + 1, 0);
    reshaped[static_cast<std::size_t>(b)] = 1;
  };
  for (std::size_t s = 0; s < n_old; ++s)
    if (owner[full_id_[s]] != owner_[s]) {
      reshape(owner_[s]);
      reshape(owner[full_id_[s]]);
      owner_[s] = owner[full_id_[s]];
      moved = true;
    }
  auto link = [&](std::size_t id) {
    if (compact_of_[id] == kNone) {
      compact_of_[id] = full_id_.size();
      full_id_.push_back(id);
      owner_.push_back(owner[id]);
    }
    return compact_of_[id];
  };
  for (std::size_t k = seen_measurements_; k < graph.measurements.size(); ++k) {
    Measurement m = graph.measurements[k];
    m.i = link(m.i);
    m.j = link(m.j);
    graph_.measurements.push_back(std::move(m));
  }
  seen_measurements_ = graph.measurements.size();
  const std::size_t n = full_id_.size();
  graph_.num_poses = n;
  out.new_poses = n - n_old;
  out.new_measurements = graph_.measurements.size() - first_new;
  if (n == 0) return out;

  // Compact blocks: the blocks with linked poses in increasing order (as make_linked_problem
  // numbers them, so an agent keeps its protocol id once every block has linked poses). A new
  // block before an existing one, or one that lost its last linked pose, renumbers them: every
  // state is built again then (the numbering does not depend on how the data was grouped into
  // syncs, so every agent that syncs the same graph agrees on it).
  std::vector<char> present;
  for (int b : owner_) {
    if (b < 0) throw std::invalid_argument("LiveBlocks::sync: negative block");
    if (static_cast<std::size_t>(b) >= present.size())
      present.resize(static_cast<std::size_t>(b) + 1, 0);
    present[static_cast<std::size_t>(b)] = 1;
  }
  std::vector<int> order;
  for (std::size_t b = 0; b < present.size(); ++b)
    if (present[b]) order.push_back(static_cast<int>(b));
  const bool renumber = order.size() < block_of_.size() ||
                        !std::equal(block_of_.begin(), block_of_.end(), order.begin());
  if (renumber) {
    for (const auto& s : states_) retire(s);
    states_.clear();
  }
  block_of_ = std::move(order);
  compact_block_of_.assign(present.size(), -1);
  for (std::size_t c = 0; c < block_of_.size(); ++c)
    compact_block_of_[static_cast<std::size_t>(block_of_[c])] = static_cast<int>(c);
  const std::size_t renumber_from = renumber || moved ? 0 : n_old;
  blocks_.resize(n);
  for (std::size_t s = renumber_from; s < n; ++s)
    blocks_[s] = compact_block_of_[static_cast<std::size_t>(owner_[s])];
  // Assigned in place: the held states refer to this layout.
  *layout_ = make_block_layout(n, graph_.measurements, blocks_);

  const std::size_t num_blocks = block_of_.size();
  std::vector<char> touched(num_blocks, 0);
  for (std::size_t k = first_new; k < graph_.measurements.size(); ++k) {
    touched[static_cast<std::size_t>(blocks_[graph_.measurements[k].i])] = 1;
    touched[static_cast<std::size_t>(blocks_[graph_.measurements[k].j])] = 1;
  }
  for (std::size_t c = num_blocks; c < states_.size(); ++c) retire(states_[c]);
  states_.resize(num_blocks);
  for (std::size_t c = 0; c < num_blocks; ++c) {
    auto& state = states_[c];
    if (only_block_ >= 0 && block_of_[c] != only_block_) {
      retire(state);
      state.reset();
      continue;
    }
    const Eigen::MatrixXd Y0 = columns(X, layout_->poses[c]);
    const auto b = static_cast<std::size_t>(block_of_[c]);
    bool build = !state || (b < reshaped.size() && reshaped[b]);
    if (!build && touched[c]) {
      try {
        state->extend(graph_.measurements, first_new, Y0, refactor_growth_);
        ++out.extended;
      } catch (const std::invalid_argument&) {
        build = true;  // the block lost or reordered poses
      }
    } else if (!build) {
      if (moved) state->neighbours_moved(graph_.measurements);
      ++out.kept;
    }
    if (build) {
      retire(state);
      state = std::make_unique<AgentState>(static_cast<int>(c), d_, *layout_, graph_.measurements,
                                           Y0, update_);
      ++out.built;
      ++built_total_;
    }
    state->reset_iterate(Y0, columns(X, state->problem().neighbors()));
  }
  return out;
}

}  // namespace tessera
