#include <tessera/distributed/block_selection.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

const char* selection_name(SelectionRule rule) {
  switch (rule) {
    case SelectionRule::kUniform:
      return "uniform";
    case SelectionRule::kGreedy:
      return "greedy";
    case SelectionRule::kRoundRobin:
      return "round_robin";
    case SelectionRule::kGreedyNewton:
      return "greedy_newton";
  }
  return "?";
}

SelectionRule parse_selection(const std::string& name) {
  if (name == "uniform") return SelectionRule::kUniform;
  if (name == "greedy") return SelectionRule::kGreedy;
  if (name == "round_robin" || name == "round-robin") return SelectionRule::kRoundRobin;
  if (name == "greedy_newton" || name == "greedy-newton") return SelectionRule::kGreedyNewton;
  throw InputError("selection rule '" + name +
                   "' is not one of uniform, greedy, round_robin, greedy_newton");
}

const char* class_score_name(ClassScore score) {
  return score == ClassScore::kClassNorm ? "class_norm" : "largest_block";
}

ClassScore parse_class_score(const std::string& name) {
  if (name == "class_norm" || name == "norm") return ClassScore::kClassNorm;
  if (name == "largest_block" || name == "max") return ClassScore::kLargestBlock;
  throw InputError("class score '" + name + "' is not one of class_norm, largest_block");
}

namespace {

// splitmix64: a well-mixed hash of (seed, round), the same on every platform.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace

int selection_units(bool parallel, const BlockLayout& layout) {
  return parallel ? static_cast<int>(layout.colour_classes.size()) : layout.num_blocks;
}

std::vector<int> select_blocks(SelectionRule rule, bool parallel, std::uint64_t seed,
                               std::uint64_t round, const std::vector<double>& block_grad_norms,
                               const BlockLayout& layout, ClassScore class_score) {
  const int units = selection_units(parallel, layout);
  int unit = 0;
  switch (rule) {
    case SelectionRule::kUniform: {
      // Rejection-free modulo bias is < units / 2^64: negligible.
      unit = static_cast<int>(mix(mix(seed) ^ round) % static_cast<std::uint64_t>(units));
      break;
    }
    case SelectionRule::kRoundRobin:
      unit = static_cast<int>(round % static_cast<std::uint64_t>(units));
      break;
    case SelectionRule::kGreedy:
    case SelectionRule::kGreedyNewton: {
      if (parallel && class_score == ClassScore::kClassNorm) {
        // A parallel round's unit is the colour class, so its Gauss-Southwell score is the
        // class's own gradient norm (squared: the sum over its blocks), not its largest block.
        double best_sq = -1.0;
        for (std::size_t c = 0; c < layout.colour_classes.size(); ++c) {
          double sq = 0.0;
          for (int b : layout.colour_classes[c]) {
            const double g = block_grad_norms[static_cast<std::size_t>(b)];
            sq += g * g;
          }
          if (sq > best_sq) best_sq = sq, unit = static_cast<int>(c);
        }
        break;
      }
      int best = 0;
      for (int b = 1; b < layout.num_blocks; ++b)
        if (block_grad_norms[static_cast<std::size_t>(b)] >
            block_grad_norms[static_cast<std::size_t>(best)])
          best = b;
      unit = parallel ? layout.colour[static_cast<std::size_t>(best)] : best;
      break;
    }
  }
  if (parallel) return layout.colour_classes[static_cast<std::size_t>(unit)];
  return {unit};
}

}  // namespace tessera
