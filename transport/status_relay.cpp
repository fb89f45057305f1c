#include "transport/status_relay.hpp"

#include <cmath>
#include <string>

#include "transport/transport_error.hpp"

namespace tessera::transport {

namespace {
// Per bundled status (see StatusRelay::pack): the fixed fields, then the coarse terms' count
// and the terms themselves.
constexpr std::size_t kFields = 7;
}  // namespace

bool StatusRelay::add(const wire::RoundStatus& m, std::uint32_t current_epoch) {
  while (!steps_.empty() && std::get<0>(steps_.begin()->first) < current_epoch)
    steps_.erase(steps_.begin());  // abandoned by a rollback
  if (m.epoch() < current_epoch) return false;
  const Step step{m.epoch(), m.round(), m.phase()};
  auto& have = steps_[step];
  have[m.sender()] = m;
  if (have.size() != num_agents_ || !have.count(kRelayAgent)) return false;
  complete_.push_back(step);
  return true;
}

std::vector<wire::RoundStatus> StatusRelay::take_bundles(const std::string& run_id,
                                                         std::uint32_t relay) {
  std::vector<wire::RoundStatus> out;
  for (const Step& step : complete_) {
    auto it = steps_.find(step);
    if (it == steps_.end()) continue;  // dropped with its epoch
    std::vector<wire::RoundStatus> statuses;
    for (auto& [sender, m] : it->second) statuses.push_back(std::move(m));
    steps_.erase(it);
    wire::RoundStatus b;
    b.run_id(run_id);
    b.epoch(std::get<0>(step));
    b.round(std::get<1>(step));
    b.phase(std::get<2>(step));
    b.sender(relay);
    b.broadcast(true);
    b.bundle(pack(statuses));
    out.push_back(std::move(b));
  }
  complete_.clear();
  return out;
}

std::vector<double> StatusRelay::pack(const std::vector<wire::RoundStatus>& statuses) {
  std::vector<double> out;
  out.reserve(kFields * statuses.size());
  for (const auto& s : statuses) {
    out.push_back(static_cast<double>(s.sender()));
    out.push_back(s.cost());
    out.push_back(s.grad_norm_sq());
    out.push_back(s.block_grad_norm());
    out.push_back(s.restart_vote() ? 1.0 : 0.0);
    out.push_back(s.done_vote() ? 1.0 : 0.0);
    out.push_back(static_cast<double>(s.coarse().size()));
    out.insert(out.end(), s.coarse().begin(), s.coarse().end());
  }
  return out;
}

std::vector<wire::RoundStatus> StatusRelay::unpack(const wire::RoundStatus& bundle) {
  const std::vector<double>& v = bundle.bundle();
  auto malformed = [&]() {
    return TransportError("malformed message: status bundle from agent " +
                          std::to_string(bundle.sender()) + " has " + std::to_string(v.size()) +
                          " values, which do not split into statuses");
  };
  std::vector<wire::RoundStatus> out;
  for (std::size_t k = 0; k < v.size();) {
    if (v.size() - k < kFields) throw malformed();
    const double count = v[k + 6];
    if (!(count >= 0 && count <= static_cast<double>(v.size() - k - kFields)) ||
        std::floor(count) != count)
      throw malformed();
    const std::size_t terms = static_cast<std::size_t>(count);
    const double sender = v[k];
    if (!(sender >= 0 && sender < 4294967296.0) || std::floor(sender) != sender)
      throw TransportError("malformed message: status bundle from agent " +
                           std::to_string(bundle.sender()) + " names sender " +
                           std::to_string(sender));
    wire::RoundStatus s;
    s.run_id(bundle.run_id());
    s.epoch(bundle.epoch());
    s.round(bundle.round());
    s.phase(bundle.phase());
    s.broadcast(true);
    s.sender(static_cast<std::uint32_t>(sender));
    s.cost(v[k + 1]);
    s.grad_norm_sq(v[k + 2]);
    s.block_grad_norm(v[k + 3]);
    s.restart_vote(v[k + 4] != 0.0);
    s.done_vote(v[k + 5] != 0.0);
    const auto first = v.begin() + static_cast<std::ptrdiff_t>(k + kFields);
    s.coarse(std::vector<double>(first, first + static_cast<std::ptrdiff_t>(terms)));
    out.push_back(std::move(s));
    k += kFields + terms;
  }
  return out;
}

}  // namespace tessera::transport
