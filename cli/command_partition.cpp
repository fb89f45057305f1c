// `tessera partition GRAPH --parts N [--preset P] [--eps E] [--seed S] [--islands K]
// [--objective O] [--colour-slack F] [--out FILE] [--json FILE]`:
// splits a pose graph (g2o) or a METIS graph into N balanced blocks and reports the quality.

#include <cstdio>
#include <fstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/metis_reader.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partition_metrics.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/partition/robot_partition.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "arguments.hpp"
#include "commands.hpp"
#include "json_writer.hpp"

namespace tessera::cli {
namespace {

const char* const kHelp =
    "usage: tessera partition GRAPH --parts N [--preset P] [--eps E] [--seed S]\n"
    "                         [--islands K] [--objective cut|rounds] [--colour-slack F]\n"
    "                         [--time-limit S] [--stall-steps K]\n"
    "                         [--out FILE] [--json FILE] [--format F]\n"
    "\n"
    "Splits the poses of GRAPH into N balanced blocks (one per agent) with few cut edges,\n"
    "using only the graph's structure. Every block holds at most floor((1+eps)*ceil(n/N))\n"
    "poses. Cut edges count every measurement between two blocks (parallel ones included).\n"
    "GRAPH is a g2o pose graph or a METIS graph (.graph/.metis, or detected by content).\n"
    "\n"
    "options:\n"
    "  --parts N      number of blocks, 1..64 and at most the number of poses (required)\n"
    "  --preset P     sequential | fast | eco | strong | highest (default strong)\n"
    "                 sequential: N contiguous id ranges, sizes differing by at most one\n"
    "                 (a file with N robots, e.g. GTSAM keys: each robot its own poses);\n"
    "                 fast/eco/strong/highest: multilevel partitioner, increasing effort\n"
    "                 (see docs/partitioning.md)\n"
    "  --eps E        balance slack, 0..1 (default 0.03)\n"
    "  --seed S       non-negative integer; same seed, same partition (default 1)\n"
    "  --islands K    strong/highest: independent searches, each on its own thread and each\n"
    "                 with the preset's whole budget (K x the CPU); 0 = the preset's own\n"
    "                 (strong 1, highest 2), else 1..8; highest adds a short search (a fifth\n"
    "                 of the budget) unless K = 1 or that is fewer steps than its population.\n"
    "                 The partition depends on K and the seed, never on the machine\n"
    "                 (default 0)\n"
    "  --objective O  cut: fewest cut edges (default); rounds: then fewer colours of the\n"
    "                 block adjacency graph, i.e. more blocks per IRBCD round, for at most\n"
    "                 --colour-slack more cut (docs/partitioning.md)\n"
    "  --colour-slack F  objective rounds: largest relative cut increase, 0..10 (default 0.25)\n"
    "  --time-limit S strong/highest/eco: stop the search after S seconds of wall time\n"
    "                 (default 0: no cap; with a cap the partition depends on the machine)\n"
    "  --stall-steps K  strong/highest: end the search after K steps in a row without a\n"
    "                 better cut (default 0: the preset's window, max(40, a third of its steps))\n"
    "  --out FILE     write the block id of pose i on line i (0-based, one per line)\n"
    "  --json FILE    write the figures as one JSON object to FILE ('-' for stdout)\n"
    "  --format F     g2o | metis: override the format detection (default: detected from\n"
    "                 the file)\n"
    "  --help         show this text\n"
    "\n"
    "exit status: 0 on success, 2 on bad input (the message says what is wrong).\n";

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A g2o/TORO file's pose keys go to `keys` (its robots make the sequential baseline).
GraphStructure load_structure(const std::string& path, const std::string& format, PoseKeys& keys) {
  bool metis;
  if (format == "metis") {
    metis = true;
  } else if (format == "g2o") {
    metis = false;
  } else if (!format.empty()) {
    throw InputError("option --format: '" + format + "' is not one of g2o, metis");
  } else if (ends_with(path, ".graph") || ends_with(path, ".metis")) {
    metis = true;
  } else if (ends_with(path, ".g2o")) {
    metis = false;
  } else {
    if (!std::ifstream(path)) throw InputError(path, 0, "cannot open file");
    metis = looks_like_metis(path);
  }
  if (metis) return read_metis(path);
  G2oReadResult read = read_g2o_file(path);
  keys = std::move(read.keys);
  return graph_structure_from_pose_graph(read.graph);
}

std::string result_json(const GraphStructure& g, const PartitionOptions& o,
                        const PartitionResult& r) {
  const auto& m = r.metrics;
  std::vector<JsonObject> trace;
  for (const auto& p : r.trace)
    trace.push_back(JsonObject()
                        .add("phase", p.name)
                        .add("detail", p.detail)
                        .add("cut", static_cast<long long>(p.cut))
                        .add("ms", p.ms));
  return JsonObject()
      .add("graph", g.source)
      .add("n", g.num_vertices)
      .add("edges", g.total_edge_weight())
      .add("pairs", g.num_pairs())
      .add("parts", o.parts)
      .add("preset", preset_name(o.preset))
      .add("eps", o.eps)
      .add("seed", static_cast<long long>(o.seed))  // parsed from a non-negative long
      .add("islands", o.islands)
      .add("objective", objective_name(o.objective))
      .add("cut_edges", m.cut_edges)
      .add("cut_pairs", m.cut_pairs)
      .add("block_sizes", m.block_sizes)
      .add("max_block", m.max_block)
      .add("max_block_bound", r.max_block_size)
      .add("max_block_ratio", m.max_block_ratio)
      .add("imbalance", m.imbalance)
      .add("cvolume", m.cvolume)
      .add("boundary_vertices", m.boundary_vertices)
      .add("adjacent_block_pairs", r.adjacent_block_pairs)
      .add("colours", r.colours)
      .add("time_ms", r.time_ms)
      .add("cpu_ms", r.cpu_ms)
      .add("trace", trace)
      .str();
}

}  // namespace

int run_partition(const Args& args) {
  Arguments a(args,
              {"parts", "preset", "eps", "seed", "islands", "objective", "colour-slack",
               "time-limit", "stall-steps", "out", "json", "format"},
              {"help"});
  if (a.has("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (a.positional().size() != 1)
    throw InputError(std::string(a.positional().empty() ? "missing GRAPH" : "more than one GRAPH") +
                     " (usage: tessera partition GRAPH --parts N [--preset P]; see --help)");
  if (!a.has("parts")) throw InputError("option --parts N is required (see --help)");
  PartitionOptions options;
  const long parts = a.get_long("parts", 0);
  if (parts < 1 || parts > 64)
    throw InputError("option --parts: " + std::to_string(parts) + " is outside 1..64");
  options.parts = static_cast<int>(parts);
  options.preset = parse_preset(a.get_or("preset", "strong"));
  options.eps = a.get_double("eps", 0.03);
  if (options.eps < 0.0 || options.eps > 1.0)
    throw InputError("option --eps: " + a.get_or("eps", "") + " is outside 0..1");
  const long seed = a.get_long("seed", 1);
  if (seed < 0) throw InputError("option --seed: must be a non-negative integer");
  options.seed = static_cast<std::uint64_t>(seed);
  const long islands = a.get_long("islands", 0);
  if (islands < 0 || islands > 8)
    throw InputError("option --islands: " + std::to_string(islands) + " is outside 0..8");
  options.islands = static_cast<int>(islands);
  options.objective = parse_objective(a.get_or("objective", "cut"));
  options.colour_cut_slack = a.get_double("colour-slack", options.colour_cut_slack);
  if (!(options.colour_cut_slack >= 0.0 && options.colour_cut_slack <= 10.0))
    throw InputError("option --colour-slack: " + a.get_or("colour-slack", "") +
                     " is outside 0..10");
  options.time_limit_s = a.get_double("time-limit", 0.0);
  if (!(options.time_limit_s >= 0.0))
    throw InputError("option --time-limit: must be >= 0 seconds (0 = no cap)");
  const long stall = a.get_long("stall-steps", 0);
  if (stall < 0 || stall > 1000000)
    throw InputError("option --stall-steps: " + std::to_string(stall) + " is outside 0..1000000");
  options.stall_steps = static_cast<int>(stall);
  options.validate();

  PoseKeys keys;
  const GraphStructure g = load_structure(a.positional()[0], a.get_or("format", ""), keys);
  PartitionResult r = partition_graph(g, options);
  if (options.preset == PartitionPreset::kSequential)  // a multi-robot file: each robot its poses
    if (auto by_robot = robot_partition(keys, g.num_vertices, options.parts)) {
      r.assignment = std::move(*by_robot);
      r.metrics = compute_partition_metrics(g, r.assignment, options.parts);
    }
  const auto& m = r.metrics;

  if (auto out = a.get("out")) {
    std::string text;
    text.reserve(r.assignment.size() * 3);
    for (int b : r.assignment) text += std::to_string(b) + "\n";
    write_output(*out, text);
  }
  const bool json_stdout = a.get("json") && *a.get("json") == "-";
  if (auto json = a.get("json")) write_output(*json, result_json(g, options, r));
  if (json_stdout) return 0;  // keep stdout valid JSON

  std::printf("graph:        %s (%zu poses, %zu measurements, %zu distinct pairs)\n",
              g.source.c_str(), g.num_vertices, g.total_edge_weight(), g.num_pairs());
  std::printf("partition:    %d blocks, preset %s, eps %g, seed %llu\n", options.parts,
              preset_name(options.preset), options.eps,
              static_cast<unsigned long long>(options.seed));
  std::printf("cut edges:    %zu (%.2f%% of measurements), cut pairs %zu\n", m.cut_edges,
              g.total_edge_weight() ? 100.0 * m.cut_edges / g.total_edge_weight() : 0.0,
              m.cut_pairs);
  std::printf("block sizes: ");
  for (auto s : m.block_sizes) std::printf(" %zu", s);
  std::printf("  (largest %zu, bound %zu)\n", m.max_block, r.max_block_size);
  std::printf("balance:      max_block_ratio %.4f, imbalance %.4f\n", m.max_block_ratio,
              m.imbalance);
  std::printf("cvolume:      %.4f\n", m.cvolume);
  std::printf("quotient:     %d adjacent block pairs, %d colours (objective %s)\n",
              r.adjacent_block_pairs, r.colours, objective_name(options.objective));
  std::printf("time:         %.1f ms (cpu %.1f ms)\n", r.time_ms, r.cpu_ms);
  return 0;
}

}  // namespace tessera::cli
