#pragma once
// Who takes part in each epoch of an online run over DDS, without DDS (the agent's loop is
// agent/online_agent.cpp, docs/online.md "Online agents over DDS"). Agent 0 starts alone at
// epoch 0; the lead of an epoch (its lowest member) admits at the next epoch every agent heard
// from (a hello or a report), so the run needs no start barrier. After a take-over the lost
// agents are never heard from again, their robots' data is absorbed by their blocks' adopters,
// and the run goes on at an epoch no survivor has used (reports of lower epochs are stale).

#include <cstdint>
#include <map>
#include <set>
#include <tessera/online/absorb_gate.hpp>
#include <vector>

namespace tessera::runtime {

class OnlineMembership {
 public:
  /// Agents 0..robots-1 may take part (one per robot).
  explicit OnlineMembership(int robots);

  /// The members of `epoch` (the lead's report of the epoch before said so). Throws
  /// std::out_of_range when no report of the lead named them yet.
  const std::set<std::uint32_t>& members(std::uint32_t epoch) const;
  bool is_member(std::uint32_t agent, std::uint32_t epoch) const;
  /// The member that admits joiners, asks for certificates and writes the answer: the lowest
  /// member of `epoch` (agent 0 while none is known, or unless it was lost).
  std::uint32_t lead_of(std::uint32_t epoch) const;
  /// Whether `robot`'s batches may enter at `epoch`: its agent is a member, or it was lost and
  /// its block's adopter absorbs them. A robot's data otherwise waits for its agent.
  bool absorbs(std::uint32_t robot, std::uint32_t epoch) const;

  /// What enters at `epoch`: what every member holds (`held`, one per member: the element-wise
  /// minimum), of the robots absorbed at `epoch` only; another robot's data waits for its agent.
  Watermarks entering(const std::vector<Watermarks>& held, std::uint32_t epoch) const;

  /// Agent `agent` said hello or reported. Agents outside 0..robots-1 and lost agents are not
  /// counted.
  void heard_from(std::uint32_t agent);
  /// The lead's report of `epoch` named `next` as the members of epoch + 1.
  void admit(std::uint32_t epoch, const std::vector<std::uint32_t>& next);
  /// What the lead of `epoch` names as the next members: the members and every agent heard
  /// from, but for the non-members among `lost_now` (an agent that said hello and died before
  /// it was admitted is not admitted).
  std::vector<std::uint32_t> next_members(std::uint32_t epoch,
                                          const std::vector<std::uint32_t>& lost_now) const;
  /// An agent heard from that is not a member of `epoch` waits to be admitted.
  bool joiner_waiting(std::uint32_t epoch) const;

  /// The survivors took over the blocks of `lost` and go on at `next_epoch` with `survivors`:
  /// the lost agents are never heard from again and the epochs below `next_epoch` are
  /// abandoned.
  void taken_over(const std::set<std::uint32_t>& lost, const std::set<std::uint32_t>& survivors,
                  std::uint32_t next_epoch);
  /// Reports of `epoch` belong to an epoch abandoned at a take-over.
  bool abandoned(std::uint32_t epoch) const { return epoch < floor_; }
  /// Whether `agent` was lost and its block taken over.
  bool lost(std::uint32_t agent) const { return lost_.count(agent) > 0; }

 private:
  std::uint32_t robots_;
  std::map<std::uint32_t, std::set<std::uint32_t>> members_{{0, {0}}};
  std::set<std::uint32_t> heard_;  // agents heard from (hello or report)
  std::set<std::uint32_t> lost_;   // members lost and taken over
  std::uint32_t floor_ = 0;        // epochs below it were abandoned at a take-over
};

}  // namespace tessera::runtime
