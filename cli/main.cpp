// `tessera`: the command-line front end. Dispatches to one subcommand per file.

#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <tessera/util/input_error.hpp>
#include <tessera/util/resource_error.hpp>

#include "commands.hpp"

namespace {

struct Command {
  const char* name;
  int (*run)(const tessera::cli::Args&);
  const char* summary;
};

const Command kCommands[] = {
    {"info", tessera::cli::run_info, "describe a pose graph (poses, edges, dimension, components)"},
    {"generate", tessera::cli::run_generate, "write a synthetic multi-robot pose graph (g2o)"},
    {"solve", tessera::cli::run_solve, "optimise a pose graph (centralized or distributed)"},
    {"partition", tessera::cli::run_partition, "split a graph into balanced blocks"},
    {"launch", tessera::cli::run_launch, "run a distributed solve as DDS processes on this host"},
    {"eval", tessera::cli::run_eval, "accuracy of an estimate against ground truth (ATE, RPE)"},
    {"plot", tessera::cli::run_plot, "draw trajectories and loop closures into a PNG"},
    {"replay", tessera::cli::run_replay, "play a multi-robot graph onto the online input topic"},
};

void print_usage() {
  std::printf("usage: tessera <command> [options]   (tessera <command> --help for details)\n\n");
  for (const auto& c : kCommands) std::printf("  %-10s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    print_usage();
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  tessera::cli::Args args(argv + 2, argv + argc);
  for (const auto& c : kCommands) {
    if (name != c.name) continue;
    try {
      return c.run(args);
    } catch (const tessera::InputError& e) {
      std::fprintf(stderr, "tessera %s: error: %s\n", c.name, e.what());
      return 2;
    } catch (const tessera::ResourceError& e) {  // not a bug: a limit of this machine
      std::fprintf(stderr, "tessera %s: error: out of resources: %s\n", c.name, e.what());
      return 1;
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr,
                   "tessera %s: error: out of resources: out of memory (an allocation failed)\n",
                   c.name);
      return 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tessera %s: internal error: %s\n", c.name, e.what());
      return 3;
    }
  }
  std::fprintf(stderr, "tessera: unknown command '%s'\n\n", name.c_str());
  print_usage();
  return 2;
}
