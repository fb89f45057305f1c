// tessera-coordinator: the lightweight process of a distributed run. It waits for the N
// agents, partitions the graph structure they announce (never measurement values),
// publishes the assignment and gathers the final estimate. See docs/dds-runtime.md.
//
// The body is coordinator_main() (coordinator_entry.cpp), which `tessera launch`'s fork
// server also runs in its forked child.

#include "coordinator/coordinator_entry.hpp"
#include "transport/fastdds/process_exit.hpp"

int main(int argc, char** argv) {
  tessera::transport::exit_process(tessera::coordinator::coordinator_main(argc, argv));
}
