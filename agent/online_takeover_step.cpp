#include "agent/online_takeover_step.hpp"

namespace tessera::agent {

TakeoverStepResult takeover_step(
    transport::OnlineChannel& channel, runtime::OnlineAgentView& view,
    const std::set<std::uint32_t>& members, const OwnVote& mine, double timeout_s,
    const std::function<std::vector<transport::OnlineReportSample>()>& take_votes,
    const std::function<void(const Watermarks&)>& wait_to_hold) {
  TakeoverStepResult out;
  out.vote = hold_takeover_vote(channel, members, mine, timeout_s, take_votes);
  // The survivors are at most one epoch boundary apart: the ones behind enter what the one
  // ahead entered, so all hold the same graph before the blocks move.
  const Watermarks target = out.vote.entered;
  wait_to_hold(target);
  view.enter(target);
  for (const auto& [a, v] : out.vote.votes)
    if (a != mine.me && v.dim != 0) view.apply_block(v.pose_ids, v.data, v.rank);
  out.moves = view.take_over(out.vote.lost);
  return out;
}

cli::JsonObject lost_for_good_fault(const TakeoverStepResult& step, double noticed_at_s,
                                    double taken_over_at_s, std::uint32_t epoch,
                                    std::size_t total_poses) {
  std::vector<std::size_t> lost_ids(step.vote.lost.begin(), step.vote.lost.end());
  std::vector<std::size_t> survivor_ids(step.vote.survivors.begin(), step.vote.survivors.end());
  cli::JsonObject f;
  f.add("kind", "lost_for_good")
      .add("lost_agents", lost_ids)
      .add("survivors", survivor_ids)
      .add("noticed_at_s", noticed_at_s)
      .add("taken_over_at_s", taken_over_at_s)
      .add("epoch", static_cast<long long>(epoch))
      .add("total_poses", total_poses)
      .add("moved_poses", step.moves.moved)
      .add("cut_edges_after", step.moves.cut_after);
  return f;
}

}  // namespace tessera::agent
