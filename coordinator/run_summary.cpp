#include "coordinator/run_summary.hpp"

#include <algorithm>
#include <optional>
#include <vector>

#include "certificate_output.hpp"
#include "heap_pages_json.hpp"
#include "json_writer.hpp"
#include "robust_args.hpp"
#include "runtime/peak_memory.hpp"

namespace tessera::coordinator {
namespace {

// A field of one of agent 0's reports, or null when the report did not come.
template <class Report, class T>
std::optional<double> field(const std::optional<Report>& report, T Report::*member) {
  return report ? std::optional<double>((*report).*member) : std::nullopt;
}

// Seconds as milliseconds; null stays null.
std::optional<double> ms(std::optional<double> s) {
  return s ? std::optional<double>(1000 * *s) : std::nullopt;
}

}  // namespace

std::string run_summary_json(const RunSummaryInputs& in) {
  const CoordinatorOptions& o = in.options;
  const ReportedResults& r = in.reports;
  const LossRecord& L = in.losses;
  std::uint64_t total_bytes = 0;
  for (auto b : in.merged.bytes) total_bytes += b;
  const auto final_value = [&](double v) {
    return r.have_final_report ? std::optional<double>(v) : std::nullopt;
  };
  // Mean wall time of one round (status of round k to status of round k+1), or null.
  const double rounds_ms = r.last_status_ms - r.first_status_ms;
  cli::JsonObject j;
  j.add("algorithm", o.algorithm.empty() ? "irbcd" : o.algorithm)
      .add("init", o.init)
      .add("graph", o.graph_name)
      .add("poses", in.structure.num_poses)
      .add("edges", in.structure.num_measurements)
      .add("d", in.structure.d)
      .add("rank", static_cast<long long>(o.rank ? o.rank : 5))
      .add("iterations", static_cast<long long>(in.merged.rounds))
      .add("grad_norm", final_value(r.final_report.grad_norm))
      .add("cost", final_value(r.final_report.cost))
      // The final cost's relative gap to the optimum given by --reference-cost.
      .add("reference_cost",
           o.reference_cost > 0 ? std::optional<double>(o.reference_cost) : std::nullopt)
      .add("rel_gap_to_reference",
           o.reference_cost > 0 && r.have_final_report
               ? std::optional<double>((r.final_report.cost - o.reference_cost) / o.reference_cost)
               : std::nullopt)
      .add("certified",
           r.certificate ? std::optional<bool>(r.certificate->certified) : std::nullopt)
      .add("wall_s", in.total_ms / 1000.0)
      .add("restarts", static_cast<long long>(r.final_report.restarts))
      .add("bytes_exchanged", static_cast<long long>(total_bytes))
      .add("rollbacks", static_cast<long long>(L.rollbacks))
      .add("run_id", o.net.session.run_id)
      .add("domain", static_cast<long long>(in.domain))
      .add("agents", static_cast<long long>(o.agents))
      .add("dim", in.structure.d)
      .add("num_poses", in.structure.num_poses)
      .add("num_measurements", in.structure.num_measurements)
      .add("partition", o.partition)
      .add("cut_edges", in.partition.cut_edges)
      .add("rounds", static_cast<long long>(in.merged.rounds))
      .add("discovery_ms", in.discovery_ms)
      .add("partition_ms", in.partition.ms)
      .add("partition_early", in.partition.early)
      .add("partition_cpu_ms", in.partition.cpu_ms)
      .add("partition_wait_ms", in.partition.wait_ms)
      .add("partition_nice", in.partition.thread_nice)
      .add("solve_ms", in.solve_ms)
      .add("rounds_ms", rounds_ms)
      .add("ms_per_round", r.completed_statuses > 1
                               ? std::optional<double>(rounds_ms / (r.completed_statuses - 1))
                               : std::nullopt)
      .add("total_ms", in.total_ms)
      // Agent 0's clock: core's protocol (rounds + certificate + escapes) and the rounding.
      .add("agent_solve_ms", ms(field(r.phase_times, &agent::PhaseTimesReport::solve_s)))
      .add("rounding_ms", ms(field(r.phase_times, &agent::PhaseTimesReport::rounding_s)))
      .add("rounding_cg_iterations",
           field(r.phase_times, &agent::PhaseTimesReport::rounding_cg_iterations))
      // The rounding's exact interface solve's poses (0: the CG solved the translations;
      // rounding_translations below says which) and its message steps.
      .add("rounding_interface_poses",
           field(r.phase_times, &agent::PhaseTimesReport::rounding_interface_poses))
      .add("rounding_message_steps",
           field(r.phase_times, &agent::PhaseTimesReport::rounding_message_steps))
      // Agent 0's set-up: its initialisation stage and hand-off (runtime/early_chordal.hpp).
      .add("init_ms", ms(field(r.setup, &agent::SetupTimesReport::initialization_s)))
      .add("handoff_ms", ms(field(r.setup, &agent::SetupTimesReport::handoff_s)))
      .add("init_early",
           r.setup ? std::optional<bool>(r.setup->initialization_early) : std::nullopt)
      .add("bytes_sent", std::vector<std::size_t>(in.merged.bytes.begin(), in.merged.bytes.end()))
      .add("hosts", in.structure.hosts);
  // Peak resident sets (MB): each agent's as it sent its final estimate, the coordinator's now,
  // and their sum, an upper bound of the run's (the processes need not peak at once, and pages
  // shared copy-on-write with the fork server count in each).
  const double mb = 1024.0 * 1024.0;
  std::vector<double> agent_mb;
  double agent_max = 0.0, run_mb = 0.0;
  for (auto b : in.merged.peak_rss) {
    agent_mb.push_back(static_cast<double>(b) / mb);
    agent_max = std::max(agent_max, agent_mb.back());
    run_mb += agent_mb.back();
  }
  const double coordinator_mb = static_cast<double>(agent::peak_resident_bytes()) / mb;
  if (r.phase_times)
    j.add("rounding_translations",
          r.phase_times->rounding_interface_poses > 0 ? "interface" : "cg");
  else
    j.add_null("rounding_translations");
  j.add("peak_rss_mb_per_agent", agent_mb)
      .add("peak_rss_mb_agent_max", agent_max)
      .add("peak_rss_mb_coordinator", coordinator_mb)
      .add("peak_rss_mb_run", run_mb + coordinator_mb);
  cli::add_heap_pages(j);
  if (in.timeline)
    j.add("timeline_ms", in.timeline->json())
        .add("started_monotonic_ms", in.timeline->started_monotonic_ms());
  if (L.epoch > 0) {  // the permanent-loss record (docs/fault-tolerance.md)
    cli::JsonObject f;
    std::vector<std::size_t> lost(L.lost.begin(), L.lost.end());
    std::vector<std::size_t> survivors(L.expected.begin(), L.expected.end());
    f.add("kind", "lost_for_good")
        .add("lost_agents", lost)
        .add("round", static_cast<long long>(L.last_round))
        .add("survivors", survivors)
        .add("moved_poses", L.moved_poses)
        .add("cut_edges_after", L.cut_edges)
        .add("repartition_at_s", L.at_ms / 1000.0)
        .add("epoch", static_cast<long long>(L.epoch));
    j.add("fault", f);
  } else {
    j.add_null("fault");
  }
  if (r.certificate) {
    j.add("min_eigenvalue", r.certificate->min_eigenvalue)
        .add("certificate_rounds", static_cast<long long>(r.certificate->rounds))
        .add("final_rank", static_cast<long long>(r.certificate->final_rank));
    add_certificate_bound(j, r.certificate->bound, r.final_report.cost);
    if (r.certificate_bytes)
      j.add("certificate_bytes", static_cast<long long>(r.certificate_bytes->certificate_bytes))
          .add("escape_bytes", static_cast<long long>(r.certificate_bytes->escape_bytes))
          .add("escape_rounds", static_cast<long long>(r.certificate_bytes->escape_rounds));
  } else {
    j.add_null("min_eigenvalue").add_null("certificate_rounds");
    j.add("final_rank", static_cast<long long>(o.rank ? o.rank : 5));
  }
  if (r.robust) {
    cli::add_distributed_robust_fields(
        j, o.robust, *r.robust, static_cast<long long>(in.merged.rounds),
        in.structure.num_measurements, r.robust->final_refine_steps, r.robust->final_solve_stages);
  } else {
    j.add("robust", robust_kind_name(o.robust.kind));
  }
  return j.str();
}

}  // namespace tessera::coordinator
