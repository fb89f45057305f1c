#pragma once
// An online agent's estimate publication (--publish-every, --tum-dir): its robot's poses, and
// those of the lost robots whose blocks it adopted, rounded to SE(d) from the current lifted
// estimate, on topic tessera_online_estimate and as TUM snapshots.

#include <cstdint>
#include <string>

#include "runtime/online_agent_view.hpp"
#include "transport/online_channel.hpp"

namespace tessera::agent {

/// Publishes agent `id`'s robots' rounded poses at `epoch` and, when `tum_dir` is not empty,
/// replaces `tum_dir`/robot<R>.tum of each. Returns whether anything was published (nothing is
/// while the received graph has no common frame, i.e. is not connected).
bool publish_online_estimate(const runtime::OnlineAgentView& view,
                             transport::OnlineChannel& channel, std::uint32_t epoch,
                             std::uint32_t id, const std::string& tum_dir);

}  // namespace tessera::agent
