#pragma once
// The messages of GNC's own exchanges (GncAgent decides when they are sent): building them from
// one agent's view and reading them back with their checks. Pose exchanges use
// distributed/pose_block_codec.hpp, measurement values distributed/measurement_block.hpp.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/protocol/messages.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>
#include <vector>

#include "robust/gnc_lead_steps.hpp"
#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_votes.hpp"

namespace tessera {

/// Every agent but `me`, ascending: whom a status exchange waits for.
std::vector<std::uint32_t> other_agents(std::uint32_t me, int num_agents);

/// `st` as `me`'s message of `phase`, one broadcast (nothing without another agent).
void broadcast_status(RoundStatusMessage st, std::uint32_t me, std::uint32_t phase, int num_agents,
                      std::vector<OutgoingMessage>& out);

/// `m` as the pose block an exchange step expects, or std::runtime_error "agent <me>: <what>"
/// naming what arrived where.
const PoseBlockMessage& expect_pose_block(const ProtocolMessage& m, int me,
                                          const std::string& what);
/// `m` as the status an exchange step expects; the same error otherwise.
const RoundStatusMessage& expect_status(const ProtocolMessage& m, int me, const std::string& what);

/// A vote's two sums (cost, grad_norm_sq), and back.
RoundStatusMessage vote_message(const std::pair<double, double>& sums);
inline std::pair<double, double> read_vote(const RoundStatusMessage& st) {
  return {st.cost, st.grad_norm_sq};
}

/// The weights message for agent `to`: the weights of the cut measurements this agent weighs
/// whose other end `to` holds, (with weight 0) its other cut measurements that leave the
/// solve (for `to`'s block layout) and, with `low_too`, its other measurements of weight below
/// 1/2 (RobustOptions::exchanges_ride_along: with them every agent knows the rejected set GNC
/// ends with, without an exchange of its own), the weight spread (grad_norm_sq, the stop vote) and
/// the count of this agent's measurements whose weight crossed 1/2 in this update (cost, the
/// adaptive mu schedule's vote, RobustOptions::mu_step_max) and of its measurements with r^2
/// near the bound (near_bound: the early end's vote, RobustOptions::jump_band).
/// `kept_cost` (block_grad_norm) is the sender's cost over the measurements it weighs that an
/// early end at this update keeps (RobustOptions::kept_vote_rides_weights; 0 when unused).
RoundStatusMessage weights_message(std::uint32_t to, double spread, int crossed, int near_bound,
                                   const GncAgentInput& in, const GncLocalTerms& terms,
                                   const std::vector<double>& weights, bool low_too,
                                   double kept_cost = 0);

/// Checks `st` from `sender` (ids and weights match; every id is the sender's to weigh) and
/// applies it: the weights of this agent's measurements, every cut id of weight 0 to
/// `zero_cut`, every id of weight below 1/2 with its weight to `low`.
/// Throws std::runtime_error naming this agent and the sender.
void read_weights_message(const RoundStatusMessage& st, std::uint32_t sender,
                          const GncAgentInput& in, std::vector<double>& weights,
                          std::vector<std::uint64_t>& zero_cut,
                          std::vector<std::pair<std::uint64_t, double>>& low);

/// The values of the measurements this agent weighs (all, or with `rejected` non-null those not
/// in it) as agent 0 gathers them: this agent's block to send, or agent 0's own entries.
PoseBlockMessage owned_values_block(const GncAgentInput& in, const GncLocalTerms& terms,
                                    const std::vector<std::uint64_t>* rejected,
                                    std::uint32_t phase);
void append_owned_values(const GncAgentInput& in, const GncLocalTerms& terms,
                         const std::vector<std::uint64_t>* rejected, GatheredValues& values);

/// A re-check verdict: ids taken back (weight 1), then ids cut now (weight 0), then the probe's
/// (weight 0.5), and the agent's TLS cost in `cost`; and back, added to `into` (no weights:
/// every id taken back). Throws std::runtime_error on a size mismatch.
RoundStatusMessage readmitted_message(const RecheckVerdict& verdict, double tls_cost);
void read_readmitted_message(const RoundStatusMessage& st, std::uint32_t sender, int receiver,
                             RecheckVerdict& into);

/// Agent 0's message of another agent's block Y of the kept set's start (poses `ids`), then the
/// start's poses `nb_ids` of the agent's neighbours (columns of `nb`; none when empty).
PoseBlockMessage kept_start_block(const Eigen::MatrixXd& Y, const std::vector<std::size_t>& ids,
                                  int d, std::uint32_t phase, const Eigen::MatrixXd& nb = {},
                                  const std::vector<std::size_t>& nb_ids = {});
/// The own block of the kept set's start (r x (d+1)|own|) from agent 0's `block`; the
/// neighbours' poses that follow it, if any, go to `nb_out` (r x (d+1)|nb|, columns of the
/// ascending neighbour poses `nb`, zero where none came). Throws std::runtime_error naming
/// `receiver` when the block does not start with exactly the poses `own` at rank r.
Eigen::MatrixXd read_kept_start(const PoseBlockMessage& block, const std::vector<std::size_t>& own,
                                Eigen::Index r, int d, int receiver,
                                const std::vector<std::size_t>& nb, Eigen::MatrixXd& nb_out);

}  // namespace tessera
