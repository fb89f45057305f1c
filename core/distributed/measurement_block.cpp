#include "distributed/measurement_block.hpp"

#include <stdexcept>
#include <string>
#include <tessera/graph/flat_measurement.hpp>

namespace tessera {

namespace {
std::size_t entry_width(int d) {
  return static_cast<std::size_t>(kMeasurementBlockRank) * static_cast<std::size_t>(d + 1);
}
}  // namespace

PoseBlockMessage encode_measurement_block(std::uint32_t sender, std::uint32_t phase, int d,
                                          const std::vector<const Measurement*>& measurements,
                                          const std::vector<std::uint64_t>& index) {
  PoseBlockMessage m;
  m.sender = sender;
  m.phase = phase;
  m.rank = kMeasurementBlockRank;
  m.dim = static_cast<std::uint32_t>(d);
  const std::size_t width = entry_width(d);
  m.pose_ids.reserve(measurements.size());
  m.data.reserve(measurements.size() * width);
  for (std::size_t k = 0; k < measurements.size(); ++k) {
    if (index[k] > 0xFFFFFFFFull)
      throw std::runtime_error("measurement index " + std::to_string(index[k]) + " beyond 32 bits");
    m.pose_ids.push_back(static_cast<std::uint32_t>(index[k]));
    const Measurement& e = *measurements[k];
    const std::size_t start = m.data.size();
    m.data.insert(m.data.end(),
                  {static_cast<double>(e.i), static_cast<double>(e.j), e.kappa, e.tau});
    append_measurement_rt(m.data, m.data, e);  // R then t
    m.data.resize(start + width, 0.0);
  }
  return m;
}

void decode_measurement_block(const PoseBlockMessage& m, int d, std::size_t num_poses,
                              const char* what,
                              std::vector<std::pair<std::uint64_t, Measurement>>& out) {
  const std::size_t width = entry_width(d), dd = static_cast<std::size_t>(d);
  if (m.rank != kMeasurementBlockRank || m.dim != static_cast<std::uint32_t>(d) ||
      m.data.size() != m.pose_ids.size() * width)
    throw std::runtime_error(std::string(what) + ": malformed measurements from agent " +
                             std::to_string(m.sender));
  for (std::size_t k = 0; k < m.pose_ids.size(); ++k) {
    const double* v = m.data.data() + k * width;
    Measurement e;
    if (!(v[0] >= 0 && v[0] < static_cast<double>(num_poses) && v[1] >= 0 &&
          v[1] < static_cast<double>(num_poses)))
      throw std::runtime_error(std::string(what) + ": agent " + std::to_string(m.sender) +
                               " sent a measurement with a pose out of range");
    e.i = static_cast<std::size_t>(v[0]);
    e.j = static_cast<std::size_t>(v[1]);
    e.kappa = v[2];
    e.tau = v[3];
    read_measurement_rt(m.data, k * width + 4, m.data, k * width + 4 + dd * dd, d, e);
    out.emplace_back(m.pose_ids[k], std::move(e));
  }
}

}  // namespace tessera
