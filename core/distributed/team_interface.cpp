#include "distributed/team_interface.hpp"

#include <stdexcept>

#include "distributed/interface_poses.hpp"

namespace tessera {

TeamInterface team_interface(const BlockLayout& layout, Eigen::Index per_pose) {
  TeamInterface t;
  for (int b = 0; b < layout.num_blocks; ++b) {
    const std::vector<std::size_t> poses = interface_poses(layout, b);
    t.block_offset.push_back(t.size);
    t.block_size.push_back(per_pose * static_cast<Eigen::Index>(poses.size()));
    for (std::size_t pose : poses) {
      t.first.emplace(pose, t.size);
      t.size += per_pose;
    }
  }
  return t;
}

OwnInterfaceLast own_interface_last(const std::vector<std::size_t>& owned,
                                    const BlockLayout& layout, int id, const std::string& who) {
  OwnInterfaceLast out;
  std::unordered_map<std::size_t, Eigen::Index> local;
  for (std::size_t i = 0; i < owned.size(); ++i)
    local.emplace(owned[i], static_cast<Eigen::Index>(i));
  const std::vector<std::size_t> interface = interface_poses(layout, id);
  out.interior =
      static_cast<Eigen::Index>(owned.size()) - static_cast<Eigen::Index>(interface.size());
  out.slot.assign(owned.size(), -1);
  for (std::size_t k = 0; k < interface.size(); ++k) {
    auto it = local.find(interface[k]);
    if (it == local.end()) throw std::logic_error(who + ": interface pose not owned");
    out.slot[static_cast<std::size_t>(it->second)] = out.interior + static_cast<Eigen::Index>(k);
    out.local.push_back(it->second);
  }
  return out;
}

}  // namespace tessera
