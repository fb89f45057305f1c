#pragma once
// Lines the coordinator prints on stdout with --progress that tessera launch reads (besides
// the round progress, which it passes through). Plain data: `tessera` includes this without
// linking the coordinator or Fast DDS.

namespace tessera::coordinator {

/// Printed once the summary file (--summary) is complete, before the agents are told to leave:
/// launch prints the summary at once instead of after every process has exited.
inline constexpr const char* kSummaryWrittenLine = "tessera-coordinator: summary written";

}  // namespace tessera::coordinator
