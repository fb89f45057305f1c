#pragma once
// The message side of GncAgent's exchanges (GncAgent decides the steps and runs the math): what
// each exchange sends and gathers, and the state that lives from one exchange's start to the
// step after it: the votes, the neighbours' public poses, the values agent 0 gathers and the
// first inlier pass's other start. Kept apart so the state machine does not decode messages.

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
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

/// The agent's data an exchange's messages write into (a weight, rejected, re-check exchange).
struct GncExchangeTargets {
  std::vector<double>& weights;
  std::vector<std::uint64_t>& zero_cut;
  std::vector<std::pair<std::uint64_t, double>>& low_weights;
  std::vector<std::uint64_t>& rejected;
  RecheckVerdict& recheck;
  Eigen::Index rank;  // rows of the own block (the kept set's start is read at it)
};

class GncExchangeBook {
 public:
  /// All three must outlive the book (GncAgent's own members).
  GncExchangeBook(const GncAgentInput& in, const GncLocalTerms& terms, const BlockLayout& base)
      : in_(in), terms_(terms), base_(base) {}

  /// A new exchange: no votes yet.
  void begin() {
    votes_.clear();
    near_bound_.clear();
    kept_costs_.clear();
    candidate_cost_.reset();
  }
  /// The weight exchange's count of residuals near the bound (RobustOptions::jump_band): this
  /// agent's, and the sum over every agent.
  double& own_near_bound() { return near_bound_[static_cast<std::uint32_t>(in_.id)]; }
  double summed_near_bound() const;
  /// The weight exchange's cost over the kept set at TLS's verdict
  /// (RobustOptions::kept_vote_rides_weights): this agent's, and the sum over every agent.
  double& own_kept_cost() { return kept_costs_[static_cast<std::uint32_t>(in_.id)]; }
  double summed_kept_cost() const;
  /// The kept set's fresh start's cost over the kept set, when agent 0 sent it beside the start
  /// (or, at agent 0, computed it) in the running exchange; empty otherwise.
  std::optional<double>& candidate_cost() { return candidate_cost_; }
  /// This agent's vote of the current exchange (summed with the others' in agent-id order).
  std::pair<double, double>& own_vote() { return votes_[static_cast<std::uint32_t>(in_.id)]; }
  std::pair<double, double> summed_votes() const;  // every agent's, agent-id order
  double largest_vote() const;                     // of the first sums

  /// A pose exchange starts: the neighbours' poses zeroed at rank `rows` (with `both_starts`
  /// those of the other start too).
  void expect_poses(Eigen::Index rows, bool both_starts);
  /// `Y`'s public poses to every block neighbour.
  void publish(const Eigen::MatrixXd& Y, BlockKind kind, std::uint32_t phase,
               std::vector<OutgoingMessage>& out, std::uint32_t round = 0) const;
  /// Agent 0 gathers the values of the measurements the agents weigh (each measurement once;
  /// with `rejected` non-null those not in it): the others send theirs, agent 0 keeps its own
  /// and waits. Returns whom this agent waits for (the others wait for agent 0's answer).
  std::vector<int> gather_values_at_lead(std::uint32_t phase,
                                         const std::vector<std::uint64_t>* rejected,
                                         std::vector<OutgoingMessage>& out);

  /// One message of exchange `e` (as this agent's phase names it), read into the book or `to`.
  /// Throws std::runtime_error naming what arrived where.
  void read(GncExchange e, const ProtocolMessage& message, GncExchangeTargets to);

  const Eigen::MatrixXd& neighbours() const { return neighbours_; }
  /// The neighbours' poses of the last pose exchange at `poses` (global ids, each one of this
  /// agent's neighbour poses; columns in that order), e.g. a solve's AgentState::Yn.
  Eigen::MatrixXd neighbours_at(const std::vector<std::size_t>& poses) const;
  const Eigen::MatrixXd& candidate_neighbours() const { return candidate_neighbours_; }
  void forget_candidate_neighbours() { candidate_neighbours_.resize(0, 0); }
  /// The second start became the iterate: its neighbours' poses are the iterate's now.
  void adopt_candidate_neighbours() { neighbours_ = candidate_neighbours_; }
  /// The candidate start's neighbour poses when agent 0 sent (or, at agent 0, computed) them
  /// with the start: empty otherwise.
  Eigen::MatrixXd& candidate_neighbours() { return candidate_neighbours_; }
  Eigen::MatrixXd& candidate() { return candidate_; }
  GatheredValues& kept_values() { return kept_values_; }
  /// Agent 0: every measurement's value, gathered once beside the first weights (static data),
  /// from which each fresh start of a kept set takes its own (GncAgent::values_held_).
  GatheredValues& held_values() { return held_values_; }
  /// Agent 0's consistency check as another agent received it.
  const std::vector<std::uint64_t>& pcm_dropped() const { return pcm_dropped_; }

 private:
  const GncAgentInput& in_;
  const GncLocalTerms& terms_;
  const BlockLayout& base_;  // of every measurement: whose poses go where
  // Sums of the current exchange (in agent-id order: own and received values kept by sender).
  std::map<std::uint32_t, std::pair<double, double>> votes_;
  std::map<std::uint32_t, double> near_bound_;
  std::map<std::uint32_t, double> kept_costs_;
  std::optional<double> candidate_cost_;
  Eigen::MatrixXd neighbours_;  // neighbours' public poses of the current iterate
  Eigen::MatrixXd candidate_, candidate_neighbours_;  // the first inlier pass's other start
  GatheredValues kept_values_;                        // agent 0's gathers
  GatheredValues held_values_;                        // agent 0: every measurement's
  std::vector<std::uint64_t> pcm_dropped_;
};

}  // namespace tessera
