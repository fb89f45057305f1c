// tessera-agent: one robot's process in a distributed run. Thin over core/ (graph I/O,
// the round protocol) and transport/ (DDS). See docs/dds-runtime.md.
//
// The body is agent_main() (agent_entry.cpp), which `tessera launch`'s fork server also runs
// in its forked children.

#include "agent/agent_entry.hpp"
#include "transport/fastdds/process_exit.hpp"

int main(int argc, char** argv) {
  tessera::transport::exit_process(tessera::agent::agent_main(argc, argv));
}
