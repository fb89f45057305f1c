#include "runtime/agent_checkpoint.hpp"

#include <tessera/distributed/checkpoint_file.hpp>
#include <tessera/util/byte_codec.hpp>

namespace tessera::agent {

namespace {
constexpr std::uint32_t kPayloadTag = 0x41474e54;  // "AGNT": an agent's checkpoint

void put_pose(ByteWriter& w, const Pose& p) {
  w.matrix(p.R);
  w.matrix(p.t);
}

Pose get_pose(ByteReader& r) {
  Pose p;
  p.R = r.matrix("pose rotation");
  const Eigen::MatrixXd t = r.matrix("pose translation");
  if (t.cols() != 1 || t.rows() != p.R.rows() || p.R.rows() != p.R.cols())
    throw CodecError("pose of inconsistent shape");
  p.t = t.col(0);
  return p;
}
}  // namespace

std::string checkpoint_path(const std::string& dir, std::uint32_t agent_id) {
  return (dir.empty() ? std::string(".") : dir) + "/agent-" + std::to_string(agent_id) + ".ckpt";
}

std::string encode_checkpoint(const std::string& run_id, const AgentLocalData& l,
                              const std::vector<ProtocolSnapshot>& snapshots) {
  ByteWriter w;
  w.u32(kPayloadTag);
  w.string(run_id);
  w.u32(l.agent_id);
  w.u32(l.num_agents);
  w.i64(l.d);
  w.u64(l.num_poses);
  w.u32s(l.owner);
  w.u32s(l.owned);
  w.u64(l.measurements.size());
  for (const Measurement& m : l.measurements) {
    w.u64(m.i);
    w.u64(m.j);
    w.matrix(m.R);
    w.matrix(m.t);
    w.f64(m.kappa);
    w.f64(m.tau);
  }
  w.u64s(l.measurement_index);
  w.u64(l.initial.size());
  for (const Pose& p : l.initial) put_pose(w, p);
  w.u64(l.structure.size());
  for (const auto& [i, j] : l.structure) {
    w.u32(i);
    w.u32(j);
  }
  const RunOptions& o = l.options;
  w.string(o.algorithm);
  w.string(o.initialization);
  w.u32(o.rank);
  w.u32(o.max_rounds);
  w.f64(o.grad_norm_tolerance);
  w.f64(o.relative_cost_tolerance);
  w.u64(o.seed);
  w.u32(o.certify ? 1 : 0);
  w.u32(o.coarse_every);
  w.u32(o.coarse_aggregates);
  w.u32(o.coarse_smoothing);
  w.string(o.refine);  // a restarted agent must refine as the others do
  w.f64(o.refine_grad_tol);
  w.f64(o.refine_rel_tol);
  w.string(o.refine_sigma);
  w.u32(o.tangent_split_dots ? 1 : 0);  // the dot products' bits, as the others'
  w.u64(snapshots.size());
  for (const auto& s : snapshots) encode(w, s);
  return w.bytes();
}

AgentCheckpoint decode_checkpoint(const std::string& payload, const std::string& what) {
  try {
    ByteReader r(payload, what);
    if (r.u32("payload tag") != kPayloadTag)
      throw CodecError("not an agent checkpoint (wrong payload tag)");
    AgentCheckpoint c;
    c.run_id = r.string("run id");
    AgentLocalData& l = c.local;
    l.agent_id = r.u32("agent id");
    l.num_agents = r.u32("number of agents");
    l.d = static_cast<int>(r.i64("d"));
    if (l.d != 2 && l.d != 3) throw CodecError("dimension " + std::to_string(l.d));
    l.num_poses = r.u64("number of poses");
    l.owner = r.u32s("owner");
    l.owned = r.u32s("owned");
    const std::uint64_t m = r.u64("number of measurements");
    for (std::uint64_t k = 0; k < m; ++k) {
      Measurement e;
      e.i = r.u64("measurement i");
      e.j = r.u64("measurement j");
      e.R = r.matrix("measurement R");
      const Eigen::MatrixXd t = r.matrix("measurement t");
      if (t.cols() != 1 || t.rows() != l.d || e.R.rows() != l.d || e.R.cols() != l.d)
        throw CodecError("measurement of inconsistent shape");
      e.t = t.col(0);
      e.kappa = r.f64("kappa");
      e.tau = r.f64("tau");
      if (e.i >= l.num_poses || e.j >= l.num_poses)
        throw CodecError("measurement names a pose out of range");
      l.measurements.push_back(std::move(e));
    }
    l.measurement_index = r.u64s("measurement index");
    const std::uint64_t np = r.u64("number of initial poses");
    for (std::uint64_t k = 0; k < np; ++k) l.initial.push_back(get_pose(r));
    const std::uint64_t ns = r.u64("structure size");
    for (std::uint64_t k = 0; k < ns; ++k) {
      const std::uint32_t i = r.u32("structure i"), j = r.u32("structure j");
      l.structure.emplace_back(i, j);
    }
    RunOptions& o = l.options;
    o.algorithm = r.string("algorithm");
    o.initialization = r.string("initialization");
    o.rank = r.u32("rank");
    o.max_rounds = r.u32("max rounds");
    o.grad_norm_tolerance = r.f64("grad norm tolerance");
    o.relative_cost_tolerance = r.f64("relative cost tolerance");
    o.seed = r.u64("seed");
    o.certify = r.u32("certify") != 0;
    o.coarse_every = r.u32("coarse every");
    o.coarse_aggregates = r.u32("coarse aggregates");
    o.coarse_smoothing = r.u32("coarse smoothing");
    o.refine = r.string("refine");
    o.refine_grad_tol = r.f64("refine grad tolerance");
    o.refine_rel_tol = r.f64("refine relative tolerance");
    o.refine_sigma = r.string("refine sigma");
    o.tangent_split_dots = r.u32("tangent split dots") != 0;
    const std::uint64_t n = r.u64("number of snapshots");
    for (std::uint64_t k = 0; k < n; ++k) c.snapshots.push_back(decode_snapshot(r));
    r.expect_end();
    if (l.owner.size() != l.num_poses || l.measurement_index.size() != l.measurements.size())
      throw CodecError("inconsistent array lengths");
    for (std::size_t k = 1; k < c.snapshots.size(); ++k)
      if (c.snapshots[k].round <= c.snapshots[k - 1].round)
        throw CodecError("snapshot rounds are not increasing");
    return c;
  } catch (const CodecError& e) {
    throw CheckpointError("checkpoint " + what + " is not usable: " + e.what());
  }
}

AgentCheckpoint load_checkpoint(const std::string& path, const std::string& run_id,
                                std::uint32_t agent_id, std::uint32_t num_agents) {
  AgentCheckpoint c = decode_checkpoint(read_checkpoint_file(path), path);
  auto bad = [&](const std::string& why) {
    return CheckpointError("checkpoint " + path + " is not usable: " + why);
  };
  if (c.run_id != run_id)
    throw bad("it belongs to run '" + c.run_id + "', this agent is in run '" + run_id + "'");
  if (c.local.agent_id != agent_id || c.local.num_agents != num_agents)
    throw bad("it belongs to agent " + std::to_string(c.local.agent_id) + " of " +
              std::to_string(c.local.num_agents) + ", this is agent " + std::to_string(agent_id) +
              " of " + std::to_string(num_agents));
  if (c.snapshots.empty()) throw bad("it holds no round snapshot");
  for (const auto& s : c.snapshots)
    if (s.agent != static_cast<int>(agent_id)) throw bad("a snapshot of another agent");
  return c;
}

}  // namespace tessera::agent
