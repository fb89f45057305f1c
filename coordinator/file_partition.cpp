#include "coordinator/file_partition.hpp"

#include <condition_variable>
#include <exception>
#include <mutex>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/partition/robot_partition.hpp>
#include <thread>
#include <utility>

#include "coordinator/partition_priority.hpp"

namespace tessera::coordinator {

bool FilePartition::fits(const RunStructure& rs) const {
  return rs.num_poses == num_poses && rs.edge_i == edge_i && rs.edge_j == edge_j;
}

std::optional<FilePartition> partition_graph_file(const std::string& path, std::uint32_t num_agents,
                                                  const std::string& preset, std::uint64_t seed,
                                                  std::string* why, double time_limit_s) {
  try {
    FilePartition fp;
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    std::optional<std::vector<int>> by_robot;
    {
      const G2oReadResult read = read_g2o_file(path);  // values dropped at the end of this scope
      const PoseGraph& graph = read.graph;
      if (preset == "sequential")
        by_robot = robot_partition(read.keys, graph.num_poses, static_cast<int>(num_agents));
      fp.num_poses = graph.num_poses;
      pairs.reserve(graph.measurements.size());
      fp.edge_i.reserve(graph.measurements.size());
      fp.edge_j.reserve(graph.measurements.size());
      for (const Measurement& m : graph.measurements) {
        pairs.emplace_back(m.i, m.j);
        fp.edge_i.push_back(static_cast<std::uint32_t>(m.i));
        fp.edge_j.push_back(static_cast<std::uint32_t>(m.j));
      }
    }
    // The same call, on the same structure, as the partition of the announcements.
    const GraphStructure structure = make_graph_structure(fp.num_poses, pairs, path);
    fp.part = partition_for_agents(structure, num_agents, preset, seed, time_limit_s);
    if (by_robot) {  // a multi-robot file's sequential baseline: each robot keeps its poses
      fp.part.owner.assign(by_robot->begin(), by_robot->end());
      fp.part.cut_edges = 0;
      for (std::size_t e = 0; e < fp.edge_i.size(); ++e)
        fp.part.cut_edges += fp.part.owner[fp.edge_i[e]] != fp.part.owner[fp.edge_j[e]];
    }
    fp.part.early = true;
    return fp;
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return std::nullopt;
  }
}

struct FilePartitionJob::State {
  std::mutex mutex;
  std::condition_variable done_cv;
  bool done = false;
  std::optional<FilePartition> result;
  std::string why;
  std::chrono::steady_clock::time_point started, ended;
};

FilePartitionJob::FilePartitionJob(std::string path, std::uint32_t num_agents, std::string preset,
                                   std::uint64_t seed, double time_limit_s, int nice_offset)
    : state_(std::make_shared<State>()) {
  std::thread([st = state_, path = std::move(path), num_agents, preset = std::move(preset), seed,
               time_limit_s, nice_offset] {
    // Before the file's read too: it is the partition's input, in the same start-up.
    const int got_nice = lower_partition_thread_nice(nice_offset);
    const auto started = std::chrono::steady_clock::now();
    std::string why;
    std::optional<FilePartition> r =
        partition_graph_file(path, num_agents, preset, seed, &why, time_limit_s);
    if (r) r->part.thread_nice = got_nice;
    const auto ended = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(st->mutex);
    st->result = std::move(r);
    st->why = std::move(why);
    st->started = started;
    st->ended = ended;
    st->done = true;
    st->done_cv.notify_all();
  }).detach();
}

bool FilePartitionJob::ready(std::chrono::milliseconds wait) const {
  std::unique_lock<std::mutex> lock(state_->mutex);
  return state_->done_cv.wait_for(lock, wait, [&] { return state_->done; });
}

std::optional<FilePartition> FilePartitionJob::take(std::string* why,
                                                    std::chrono::steady_clock::time_point* started,
                                                    std::chrono::steady_clock::time_point* ended) {
  std::unique_lock<std::mutex> lock(state_->mutex);
  state_->done_cv.wait(lock, [&] { return state_->done; });
  if (why) *why = state_->why;
  if (started) *started = state_->started;
  if (ended) *ended = state_->ended;
  return std::move(state_->result);
}

}  // namespace tessera::coordinator
