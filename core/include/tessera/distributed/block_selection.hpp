#pragma once
// Which block(s) update in a round. Every agent evaluates the same rule on the same broadcast
// statuses, so all agents agree without a coordinator.
//
//   uniform      a block drawn uniformly at random from a stream that depends only on
//                (seed, round): stateless, so a restart or a late joiner cannot desynchronise it.
//   greedy       the block with the largest block gradient norm (ties: lowest id).
//   greedy_newton the block with the largest preconditioned gradient norm sqrt(<(2Q_BB)^-1 g, g>),
//                i.e. the largest decrease a block update predicts (Gauss-Southwell with the
//                block's curvature): a stiff block with a large gradient gains less than a soft
//                block with a smaller one. Each agent computes its score in the status.
//   round_robin  block round mod N.
// With `parallel`, the unit of choice is a colour class of the block adjacency graph: uniform
// draws a class, greedy takes the class of the greedy block, round-robin cycles the classes.
// All blocks of the class update in the round (they share no measurement).

#include <cstdint>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <vector>

namespace tessera {

enum class SelectionRule { kUniform, kGreedy, kRoundRobin, kGreedyNewton };

/// "uniform", "greedy", "round_robin", "greedy_newton".
const char* selection_name(SelectionRule rule);
/// Inverse of selection_name; throws InputError listing the valid names.
SelectionRule parse_selection(const std::string& name);

/// How greedy selection scores a colour class (parallel rounds; one block per round is the same
/// either way).
enum class ClassScore {
  kLargestBlock,  ///< The class of the block with the largest score (RBCD's and RBCD++'s greedy).
  kClassNorm      ///< The class with the largest sqrt(sum of its blocks' squared scores).
};

/// "largest_block", "class_norm".
const char* class_score_name(ClassScore score);
/// Inverse of class_score_name (also "max" and "norm"); throws InputError listing the valid names.
ClassScore parse_class_score(const std::string& name);

/// The blocks updated in `round` (ascending ids). `block_grad_norms` has one entry per block,
/// in block-id order: each block's selection score (its gradient norm, or for greedy_newton its
/// preconditioned gradient norm). `class_score` matters only for greedy rules with `parallel`;
/// ties go to the lowest block id / class index.
std::vector<int> select_blocks(SelectionRule rule, bool parallel, std::uint64_t seed,
                               std::uint64_t round, const std::vector<double>& block_grad_norms,
                               const BlockLayout& layout,
                               ClassScore class_score = ClassScore::kLargestBlock);

/// Number of selectable units: N blocks, or the number of colour classes with `parallel`.
int selection_units(bool parallel, const BlockLayout& layout);

}  // namespace tessera
