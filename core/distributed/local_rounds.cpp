#include <algorithm>
#include <cmath>
#include <tessera/distributed/local_rounds.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

void LocalRoundOptions::validate() const {
  if (!(threshold > 0 && threshold <= 1))
    throw InputError("LocalRoundOptions.threshold must be in (0, 1]");
}

LocalRounds::LocalRounds(const BlockLayout& layout, const LocalRoundOptions& options,
                         double grad_norm_tol)
    : layout_(layout),
      bound_(options.threshold * grad_norm_tol /
             std::sqrt(static_cast<double>(std::max(1, layout.num_blocks)))) {
  options.validate();
  const auto n = static_cast<std::size_t>(layout.num_blocks);
  cost_.assign(n, 0.0);
  gsq_.assign(n, 0.0);
  score_.assign(n, 0.0);
  active_.assign(n, 0);
  moved_.assign(n, 1);
}

bool LocalRounds::sends_status(int block) const {
  if (first_ || moved(block)) return true;
  for (int a : layout_.adjacent[static_cast<std::size_t>(block)])
    if (moved(a)) return true;
  return false;
}

std::vector<int> LocalRounds::status_senders() const {
  std::vector<int> out;
  for (int b = 0; b < layout_.num_blocks; ++b)
    if (sends_status(b)) out.push_back(b);
  return out;
}

void LocalRounds::record(int block, double cost, double grad_norm_sq, double score) {
  const auto b = static_cast<std::size_t>(block);
  cost_[b] = cost;
  gsq_[b] = grad_norm_sq;
  score_[b] = score;
}

double LocalRounds::cost() const {
  double f = 0.0;
  for (double c : cost_) f += c;
  return f;
}

double LocalRounds::grad_norm_sq() const {
  double g = 0.0;
  for (double s : gsq_) g += s;
  return g;
}

std::vector<double> LocalRounds::scores() const {
  std::vector<double> out(score_.size(), 0.0);
  for (std::size_t b = 0; b < out.size(); ++b)
    if (active_[b]) out[b] = score_[b];
  return out;
}

void LocalRounds::update_activity() {
  // Once active, a block stays active until the solve ends: putting it to rest resets its
  // momentum (V := Y) while the global momentum scalars keep growing, and waking it again
  // then costs more rounds than its updates save (a 1,000-pose sphere replay: twice the rounds).
  for (std::size_t b = 0; b < gsq_.size(); ++b)
    if (std::sqrt(gsq_[b]) > bound_) active_[b] = 1;
}

void LocalRounds::set_moved(const std::vector<int>& blocks) {
  first_ = false;
  moved_.assign(moved_.size(), 0);
  for (int b : blocks) moved_[static_cast<std::size_t>(b)] = 1;
}

}  // namespace tessera
