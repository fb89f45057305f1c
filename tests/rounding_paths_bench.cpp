// Not a test: the figures of scripts/bench/rounding_paths.py. The distributed rounding
// (core/runtime/distributed_rounding.hpp) run in process (one thread per agent, the code the
// DDS agents run) on the in-process solver's iterate, its translations by the CG
// (interface_max_poses = 0) and through the team's interface (the default), against core's
// round_solution (the direct solve). One line per graph and path:
//   ROUNDING_PATH graph poses agents cut rounds path interface_poses cg_iterations
//                 message_steps cost_above_direct relative_to_f cpu_ms
// usage: rounding_paths_bench [--agents N] [--refine auto|newton|none] [--path cg|interface|both]
//                             [--save DIR | --load DIR] GRAPH.g2o...
// --save DIR keeps each graph's solve (assignment, rounds, f(X), X) in DIR/NAME.solved, --load DIR
// reads it back instead of solving (so a callgrind run of one path spends no time solving).
// The solve is launch's: `eco` partition (launch's `auto` from 2,000 poses), IRBCD, gradient
// 0.01, certificate on, `--refine auto` unless --refine says otherwise. Under callgrind with
// --instr-atstart=no only the roundings are instrumented (CALLGRIND_START/STOP_INSTRUMENTATION
// around them; scripts/bench/rounding_paths.py also counts only inside
// DistributedRounding::run, not the harness's set-up of the agents). Exit 2 on bad arguments.

#include <valgrind/callgrind.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <vector>

#include "rounding_threads.hpp"

namespace {

// The solve the roundings start from, as --save writes it: agents, rounds, f(X), X's size and
// entries, the assignment.
void save(const std::string& file, const tessera::agent::RoundingCase& c) {
  std::ofstream f(file, std::ios::binary);
  const long long head[3] = {static_cast<long long>(c.solved.rounds),
                             static_cast<long long>(c.solved.X.rows()),
                             static_cast<long long>(c.solved.X.cols())};
  f.write(reinterpret_cast<const char*>(head), sizeof(head));
  f.write(reinterpret_cast<const char*>(&c.solved.relaxation_cost), sizeof(double));
  f.write(
      reinterpret_cast<const char*>(c.solved.X.data()),
      static_cast<std::streamsize>(sizeof(double) * static_cast<std::size_t>(c.solved.X.size())));
  f.write(reinterpret_cast<const char*>(c.assignment.data()),
          static_cast<std::streamsize>(sizeof(int) * c.assignment.size()));
}

bool load(const std::string& file, tessera::agent::RoundingCase& c) {
  std::ifstream f(file, std::ios::binary);
  long long head[3] = {0, 0, 0};
  if (!f.read(reinterpret_cast<char*>(head), sizeof(head))) return false;
  c.solved.rounds = static_cast<int>(head[0]);
  f.read(reinterpret_cast<char*>(&c.solved.relaxation_cost), sizeof(double));
  c.solved.X.resize(head[1], head[2]);
  f.read(
      reinterpret_cast<char*>(c.solved.X.data()),
      static_cast<std::streamsize>(sizeof(double) * static_cast<std::size_t>(c.solved.X.size())));
  c.assignment.assign(c.graph.num_poses, 0);
  f.read(reinterpret_cast<char*>(c.assignment.data()),
         static_cast<std::streamsize>(sizeof(int) * c.assignment.size()));
  if (!f) return false;
  c.solved.poses = tessera::round_solution(c.graph, c.solved.X);
  c.solved.cost = tessera::evaluate_objective(c.graph, c.solved.poses);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace tessera;
  using namespace tessera::agent;
  int agents = 5;
  std::string refine = "auto", path = "both", save_dir, load_dir;
  std::vector<std::string> graphs;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--agents" && k + 1 < argc)
      agents = std::atoi(argv[++k]);
    else if (a == "--refine" && k + 1 < argc)
      refine = argv[++k];
    else if (a == "--path" && k + 1 < argc)
      path = argv[++k];
    else if (a == "--save" && k + 1 < argc)
      save_dir = argv[++k];
    else if (a == "--load" && k + 1 < argc)
      load_dir = argv[++k];
    else
      graphs.push_back(a);
  }
  if (graphs.empty() || agents < 2 || (path != "cg" && path != "interface" && path != "both")) {
    std::fprintf(stderr,
                 "usage: rounding_paths_bench [--agents N] [--refine auto|newton|none] "
                 "[--path cg|interface|both] [--save DIR | --load DIR] GRAPH.g2o...\n");
    return 2;
  }
  for (const std::string& file : graphs) {
    RoundingCase c;
    c.graph = read_g2o(file);
    std::string name = file.substr(file.find_last_of('/') + 1);
    name = name.substr(0, name.find(".g2o"));
    std::size_t cut = 0;
    if (!load_dir.empty()) {
      if (!load(load_dir + "/" + name + ".solved", c)) {
        std::fprintf(stderr, "cannot read %s/%s.solved\n", load_dir.c_str(), name.c_str());
        return 2;
      }
      for (const Measurement& m : c.graph.measurements)
        if (c.assignment[m.i] != c.assignment[m.j]) ++cut;
    } else {
      PartitionOptions po;
      po.parts = agents;
      po.preset = PartitionPreset::kEco;
      const PartitionResult part = partition_graph(graph_structure_from_pose_graph(c.graph), po);
      c.assignment = part.assignment;
      cut = part.metrics.cut_edges;
      DistributedOptions o;
      o.algorithm = parse_algorithm("irbcd");
      o.certify = true;
      set_refine_mode(o.refine, refine);
      c.solved = solve_distributed(c.graph, c.assignment, o, c.graph.initial);
      if (!save_dir.empty()) save(save_dir + "/" + name + ".solved", c);
    }
    const double f_direct = evaluate_objective(c.graph, c.solved.poses);
    for (const char* which : {"cg", "interface"}) {
      if (path != "both" && path != which) continue;
      DistributedRoundingOptions ro;
      if (std::string(which) == "cg") ro.interface_max_poses = 0;
      const std::clock_t cpu0 = std::clock();
      CALLGRIND_START_INSTRUMENTATION;
      const Rounded r = round_in_threads(c, ro, 600.0);
      CALLGRIND_STOP_INSTRUMENTATION;
      const double cpu_ms = 1000.0 * static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
      if (!r.errors.empty()) {
        std::fprintf(stderr, "%s (%s): %s\n", name.c_str(), which, r.errors.front().c_str());
        return 1;
      }
      std::printf("ROUNDING_PATH %s %zu %d %zu %d %s %u %u %u %.3e %.3e %.1f\n", name.c_str(),
                  c.graph.num_poses, agents, cut, c.solved.rounds, which, r.interface_poses,
                  r.iterations, r.steps, r.cost - f_direct, (r.cost - f_direct) / f_direct, cpu_ms);
      std::fflush(stdout);
    }
  }
  return 0;
}
