#pragma once
// How the survivors of an online run agree that members were lost, without a coordinator
// (agent/online_agent.cpp, docs/online.md "Lost agents"). Each survivor that notices a loss
// (the member's DDS liveliness lapsed) sends one vote: the members it counts as lost, the
// epoch it was in and the batches that entered its graph. A vote naming more lost members
// than a survivor knows makes it count them too and vote again, so every survivor ends with
// the same lost set. The agreement is complete when every survivor's latest vote names
// exactly that set; then all of them compute the same outcome from the same votes:
//   - the epoch the run goes on with: one past the newest epoch any survivor was in, so the
//     abandoned epoch's leftovers (messages, reports) are never mistaken for the new one's;
//   - the graph every survivor must hold first: survivors are at most one epoch boundary
//     apart (passing one needs every member's report), so the one ahead holds the graph of
//     the element-wise maximum, and the others enter exactly those batches to reach it.

#include <cstdint>
#include <map>
#include <set>
#include <tessera/online/absorb_gate.hpp>

namespace tessera::runtime {

struct TakeoverVote {
  std::uint32_t sender = 0;
  std::set<std::uint32_t> lost;  ///< Members the sender counts as lost.
  std::uint32_t at_epoch = 0;    ///< The epoch the sender was in.
  Watermarks entered;            ///< Batches per robot in the sender's graph.
};

class TakeoverAgreement {
 public:
  /// `members`: the agents of the epoch the loss interrupted; `me` one of them.
  TakeoverAgreement(std::set<std::uint32_t> members, std::uint32_t me);

  /// This agent counts `lost` (members only; others are ignored) as lost too. Returns true
  /// when the lost set grew: this agent must vote (again).
  bool suspect(const std::set<std::uint32_t>& lost);
  /// A vote (this agent's own included). Its lost members are counted too; returns true when
  /// the lost set grew. Votes of non-members are ignored; a newer vote replaces an older one.
  bool vote(const TakeoverVote& v);

  const std::set<std::uint32_t>& lost() const { return lost_; }
  /// Some vote counts this agent as lost (its liveliness lapsed while it was alive): it must
  /// leave the run.
  bool counts_me_lost() const { return lost_.count(me_) > 0; }
  /// The members not lost.
  std::set<std::uint32_t> survivors() const;
  /// Every survivor's latest vote names exactly the lost set (and that set is not empty).
  bool complete() const;
  /// After complete(): one past the newest epoch a survivor voted from.
  std::uint32_t next_epoch() const;
  /// After complete(): element-wise maximum of the survivors' graphs.
  Watermarks entered() const;

 private:
  std::set<std::uint32_t> members_;
  std::uint32_t me_;
  std::set<std::uint32_t> lost_;
  std::map<std::uint32_t, TakeoverVote> votes_;
};

}  // namespace tessera::runtime
