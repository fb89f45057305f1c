#include <tessera/distributed/agent_factory.hpp>
#include <tessera/distributed/block_selection.hpp>
#include <tessera/distributed/irbcd.hpp>
#include <tessera/distributed/rbcd_plus_plus.hpp>

namespace tessera {

std::unique_ptr<MomentumScheme> make_momentum_scheme(const DistributedOptions& options,
                                                     const BlockLayout& layout, double variables) {
  const int units = selection_units(options.parallel, layout);
  if (options.algorithm == DistributedAlgorithm::kRbcdPlusPlus)
    return std::make_unique<RbcdPlusPlusScheme>(options.rbcd_plus_plus, units);
  if (options.algorithm == DistributedAlgorithm::kIrbcd) {
    const double n =
        options.irbcd.dimension == IrbcdDimension::kUnits ? static_cast<double>(units) : variables;
    return std::make_unique<IrbcdScheme>(options.irbcd, n);
  }
  return nullptr;
}

RoundConfig make_round_config(const DistributedOptions& options, const MomentumScheme* scheme) {
  RoundConfig config;
  config.selection = options.selection;
  config.parallel = options.parallel;
  config.seed = options.seed;
  config.grad_norm_tol = options.grad_norm_tol;
  config.max_rounds = options.max_rounds;
  config.rel_cost_decrease_tol = options.rel_cost_decrease_tol;
  config.update = options.algorithm_block_update();
  config.scheme = scheme;
  config.coarse = options.coarse;
  config.local = options.local_rounds;
  return config;
}

}  // namespace tessera
