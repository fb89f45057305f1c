// Checkpoints and coordinated rollback in core (no DDS): a run resumed by every agent from
// its snapshot of the same round -- through the checkpoint file -- finishes with iterates
// bit-identical to the uninterrupted run; checkpoint files are written atomically and a
// torn, truncated or corrupted one is refused with an error naming the file.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <tessera/distributed/checkpoint_file.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>

#include "random_graph.hpp"
#include "round_agents.hpp"

namespace tessera {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("tessera_ckpt_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

using test::AgentsOfRun;

PoseGraph test_graph() {
  test::RandomGraphSpec spec;
  spec.d = 3;
  spec.poses = 60;
  spec.loop_closures = 30;
  spec.seed = 11;
  return test::random_pose_graph(spec);
}

void expect_same_run(const AgentsOfRun& a, const AgentsOfRun& b) {
  for (std::size_t k = 0; k < a.agents.size(); ++k) {
    EXPECT_TRUE(a.states[k]->Y == b.states[k]->Y) << "agent " << k << ": final Y differs";
    EXPECT_EQ(a.agents[k]->rounds(), b.agents[k]->rounds());
    EXPECT_EQ(a.agents[k]->restarts(), b.agents[k]->restarts());
    EXPECT_EQ(a.agents[k]->stop_reason(), b.agents[k]->stop_reason());
    const auto &ta = a.agents[k]->trace(), &tb = b.agents[k]->trace();
    ASSERT_EQ(ta.size(), tb.size());
    for (std::size_t r = 0; r < ta.size(); ++r) {
      EXPECT_EQ(ta[r].round, tb[r].round);
      EXPECT_EQ(ta[r].cost, tb[r].cost) << "round " << r;  // bit-identical, not approximately
      EXPECT_EQ(ta[r].grad_norm, tb[r].grad_norm);
      EXPECT_EQ(ta[r].selected, tb[r].selected);
      EXPECT_EQ(ta[r].restart, tb[r].restart);
    }
  }
}

// Runs to the end while every agent records its snapshot of round `k`; then a second set of
// agents (fresh objects, as after a crash) resumes from those snapshots, read back from
// checkpoint files, and must finish exactly like the first.
void check_rollback(DistributedAlgorithm algorithm, double restart_c, int k,
                    DeliveryOrder resume_order, int* restarts_seen = nullptr) {
  const PoseGraph g = test_graph();
  DistributedOptions opt;
  opt.algorithm = algorithm;
  opt.irbcd.restart_c = restart_c;
  opt.rbcd_plus_plus.restart_c = restart_c;
  opt.grad_norm_tol = 1e-3;
  opt.max_rounds = 400;
  const int N = 4;
  AgentsOfRun first(g, N, opt);
  std::map<int, ProtocolSnapshot> at_k;
  for (int b = 0; b < N; ++b)
    first.agents[static_cast<std::size_t>(b)]->set_round_observer(
        [&at_k, b, k](const ProtocolSnapshot& s) {
          if (s.round == k) at_k[b] = s;
        });
  run_in_process(first.agents, DeliveryOrder::kFifo);
  ASSERT_EQ(at_k.size(), static_cast<std::size_t>(N)) << "the run ended before round " << k;
  ASSERT_GT(first.agents[0]->rounds(), k + 5) << "pick a round well inside the run";
  if (restarts_seen) *restarts_seen = first.agents[0]->restarts();

  const fs::path dir = fresh_dir("rollback");
  std::vector<ProtocolSnapshot> loaded;
  for (int b = 0; b < N; ++b) {
    ByteWriter w;
    encode(w, at_k[b]);
    const std::string path = (dir / ("agent-" + std::to_string(b) + ".ckpt")).string();
    write_checkpoint_file(path, w.bytes());
    const std::string payload = read_checkpoint_file(path);
    ByteReader r(payload, path);
    loaded.push_back(decode_snapshot(r));
    r.expect_end();
  }
  AgentsOfRun second(g, N, opt);
  resume_in_process(second.agents, loaded, resume_order, 7);
  expect_same_run(first, second);
  fs::remove_all(dir);
}

TEST(CheckpointResume, IrbcdResumedFromRoundSnapshotsIsBitIdentical) {
  check_rollback(DistributedAlgorithm::kIrbcd, 0.0, 9, DeliveryOrder::kFifo);
}

TEST(CheckpointResume, RbcdPlusPlusWithRestartsResumedInShuffledOrderIsBitIdentical) {
  int restarts = 0;
  check_rollback(DistributedAlgorithm::kRbcdPlusPlus, 1e-4, 6, DeliveryOrder::kShuffled, &restarts);
  // The snapshot must carry the state an adaptive restart goes back to; only meaningful if
  // the run restarts somewhere after round 6.
  EXPECT_GT(restarts, 0) << "choose options that make the run restart";
}

TEST(CheckpointResume, PlainRbcdResumedAtRoundZeroIsBitIdentical) {
  check_rollback(DistributedAlgorithm::kRbcd, 0.0, 0, DeliveryOrder::kReversed);
}

TEST(CheckpointResume, SnapshotOfAnotherAgentIsRefused) {
  const PoseGraph g = test_graph();
  DistributedOptions opt;
  opt.max_rounds = 3;
  AgentsOfRun run(g, 3, opt);
  ProtocolSnapshot s;
  run.agents[1]->set_round_observer([&s](const ProtocolSnapshot& x) { s = x; });
  run_in_process(run.agents, DeliveryOrder::kFifo);
  AgentsOfRun again(g, 3, opt);
  EXPECT_THROW(again.agents[0]->resume(s), std::runtime_error);
}

// ---- the file ---------------------------------------------------------------------------

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void put_bytes(const fs::path& p, const std::string& b) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << b;
}

void expect_refused(const fs::path& p, const std::string& fragment) {
  try {
    read_checkpoint_file(p.string());
    ADD_FAILURE() << "a bad checkpoint was loaded (" << fragment << ")";
  } catch (const CheckpointError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(p.string()), std::string::npos) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

TEST(CheckpointFile, RoundTripAndReplace) {
  const fs::path dir = fresh_dir("file");
  const fs::path p = dir / "a.ckpt";
  write_checkpoint_file(p.string(), "first payload");
  EXPECT_EQ(read_checkpoint_file(p.string()), "first payload");
  write_checkpoint_file(p.string(), std::string(100000, 'x'));
  EXPECT_EQ(read_checkpoint_file(p.string()), std::string(100000, 'x'));
  write_checkpoint_file(p.string(), "");
  EXPECT_EQ(read_checkpoint_file(p.string()), "");
  // Nothing but the checkpoint is left in the folder (the temporary was renamed).
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
  fs::remove_all(dir);
}

TEST(CheckpointFile, TornTruncatedAndCorruptedFilesAreRefused) {
  const fs::path dir = fresh_dir("bad");
  const fs::path p = dir / "a.ckpt";
  std::string payload(5000, '\0');
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<char>(i * 31 + 7);
  write_checkpoint_file(p.string(), payload);
  const std::string good = bytes_of(p);

  put_bytes(p, good.substr(0, good.size() - 100));  // torn after the header
  expect_refused(p, "truncated or torn");
  put_bytes(p, good.substr(0, 10));  // torn inside the header
  expect_refused(p, "shorter than the header");
  put_bytes(p, "");
  expect_refused(p, "shorter than the header");
  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;  // one bit of the payload
  put_bytes(p, flipped);
  expect_refused(p, "checksum mismatch");
  std::string magic = good;
  magic[0] = 'X';
  put_bytes(p, magic);
  expect_refused(p, "bad magic");
  std::string version = good;
  version[8] = 99;
  put_bytes(p, version);
  expect_refused(p, "format version 99");
  put_bytes(p, good + "tail");
  expect_refused(p, "truncated or torn");
  fs::remove(p);
  expect_refused(p, "cannot open");
  fs::remove_all(dir);
}

TEST(CheckpointFile, StaleTemporaryIsNeverLoadedAndIsCleanedUp) {
  const fs::path dir = fresh_dir("stale");
  const fs::path p = dir / "a.ckpt";
  write_checkpoint_file(p.string(), "the good one");
  // A writer that died half-way (a pid that cannot exist: above the kernel's pid_max).
  const fs::path stale = dir / "a.ckpt.tmp.99999999";
  put_bytes(stale, "TSRCKPT half-written garbage");
  EXPECT_EQ(read_checkpoint_file(p.string()), "the good one");
  write_checkpoint_file(p.string(), "the next one");
  EXPECT_FALSE(fs::exists(stale)) << "the next write removes a dead writer's temporary";
  EXPECT_EQ(read_checkpoint_file(p.string()), "the next one");
  fs::remove_all(dir);
}

TEST(CheckpointFile, SnapshotDecodingRejectsGarbage) {
  const std::string junk = "\x05\x00\x00\x00\x00\x00\x00\x00\x01";
  ByteReader r(junk, "junk");
  EXPECT_THROW(decode_snapshot(r), CodecError);
  // A huge claimed matrix size is corruption, not an allocation.
  ByteWriter w;
  w.i64(0);
  w.i64(3);
  w.u64(1ull << 40);
  w.u64(1ull << 40);
  ByteReader r2(w.bytes(), "huge");
  EXPECT_THROW(decode_snapshot(r2), CodecError);
}

}  // namespace
}  // namespace tessera
