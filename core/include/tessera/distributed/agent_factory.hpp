#pragma once
// How one agent of a distributed solve is configured from the run's options, shared by the
// in-process engine (distributed_solver.cpp) and the DDS agent (core/runtime/round_loop.cpp), so
// both build identical agents and therefore produce identical iterates.

#include <Eigen/Core>
#include <memory>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/momentum.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <vector>

namespace tessera {

/// The momentum scheme of options.algorithm (null for RBCD). `variables` is the size of the
/// whole lifted iterate, r (d+1) n (IRBCD's n when its dimension option says "variables").
std::unique_ptr<MomentumScheme> make_momentum_scheme(const DistributedOptions& options,
                                                     const BlockLayout& layout, double variables);

/// The protocol configuration of `options`; `scheme` may be null (RBCD) and must outlive it.
RoundConfig make_round_config(const DistributedOptions& options, const MomentumScheme* scheme);

}  // namespace tessera
