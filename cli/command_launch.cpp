// `tessera launch`: runs a whole distributed solve on this host as separate processes, the
// coordinator and N agents talking over DDS (launch/launch.hpp does the work).

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <tessera/util/input_error.hpp>

#include "commands.hpp"
#include "launch/heap_pages.hpp"
#include "launch/launch.hpp"
#include "launch/online_launch.hpp"
#include "launch_outputs.hpp"

namespace tessera::cli {

int run_launch(const Args& given) {
  Args argv = given;
  const std::string heap_pages = take_heap_pages_flag(argv);
  const launch::HeapPages pages = launch::parse_heap_pages(heap_pages, "option --heap-pages");
  if (launch::wants_online_launch(argv)) {
    // First: this may re-run the process on huge-page heaps, which every process of the run
    // then inherits (launch/heap_pages.hpp).
    if (!launch::wants_launch_help(argv)) launch::enter_heap_pages(pages);
    return launch::run_online_launch(argv);
  }
  if (launch::wants_launch_help(argv)) {
    std::fputs(launch::launch_help().c_str(), stdout);
    std::fputs(kHeapPagesHelp, stdout);
    std::printf("\nOutputs in GRAPH's terms (one whole GRAPH file):\n%s", kLaunchOutputHelp);
    return 0;
  }
  launch::enter_heap_pages(pages);
  std::vector<std::string> rest = argv;
  const LaunchOutputs outputs = take_launch_outputs(rest);
  launch::LaunchOptions options = launch::parse_launch_options(rest);
  const bool whole_file = !options.graph.empty() && options.robot_files().empty();
  if (!whole_file || !outputs.any()) {
    if (!whole_file && (outputs.tum_dir || outputs.plot || outputs.keys || outputs.stamps))
      throw InputError("launch: --tum-dir, --plot, --keys and --stamps need one whole GRAPH file");
    // The coordinator writes them itself (solver ids and frame).
    if (outputs.out) options.forwarded.emplace_back("out", *outputs.out);
    if (outputs.tum) options.forwarded.emplace_back("tum", *outputs.tum);
    return launch::launch(std::move(options)).exit_code;
  }
  // GRAPH's ids, stamps and frame: its poses come back through a TUM file of the coordinator.
  const G2oReadResult input = read_launch_graph(outputs, options.graph);
  char tmpl[] = "/tmp/tessera-launch-out-XXXXXX";
  if (!mkdtemp(tmpl)) throw std::runtime_error("launch: cannot create a temporary folder");
  const std::string merged = std::string(tmpl) + "/merged.tum";
  struct Cleanup {
    std::string dir;
    ~Cleanup() {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    }
  } cleanup{tmpl};
  options.forwarded.emplace_back("tum", merged);
  const launch::LaunchResult result = launch::launch(std::move(options));
  if (result.exit_code == 0) write_launch_outputs(outputs, input, merged);
  return result.exit_code;
}

}  // namespace tessera::cli
