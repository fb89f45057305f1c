#pragma once
// The JSON summary of a distributed run (tessera-coordinator --summary; tessera launch
// --json reads it). Its field names are public interface: keep them, add freely.

#include <string>

#include "coordinator/coordinator_options.hpp"
#include "coordinator/final_merge.hpp"
#include "coordinator/loss_handling.hpp"
#include "coordinator/round_reports.hpp"
#include "coordinator/run_structure.hpp"
#include "coordinator/run_timeline.hpp"
#include "runtime/partition_step.hpp"

namespace tessera::coordinator {

/// Everything the summary reports, gathered by the run's steps.
struct RunSummaryInputs {
  const CoordinatorOptions& options;
  const RunStructure& structure;
  const PartitionStepResult& partition;
  const MergedEstimate& merged;
  const ReportedResults& reports;
  const LossRecord& losses;
  int domain = 0;
  double discovery_ms = 0, solve_ms = 0, total_ms = 0;
  const RunTimeline* timeline = nullptr;  ///< "timeline_ms" / "started_monotonic_ms" when set.
};

/// The summary as one JSON object. Values the run did not produce (no final report, no
/// certificate, fewer than two completed rounds, no fault) are null.
std::string run_summary_json(const RunSummaryInputs& in);

}  // namespace tessera::coordinator
