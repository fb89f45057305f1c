// GncAgent's results, read off its parts (the solve stage, the probes, the outer loop): every
// figure of GncAgentResult and the accessors of the header.

#include <tessera/robust/gnc_agent.hpp>
#include <vector>

#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_outer_loop.hpp"
#include "robust/gnc_probe_stage.hpp"
#include "robust/gnc_solve_stage.hpp"

namespace tessera {

double GncAgent::threshold_squared() const {
  return terms_->c2();
}

int GncAgent::outer_iterations() const {
  return outer_->outer();
}

bool GncAgent::weights_converged() const {
  return outer_->converged();
}

int GncAgent::total_rounds() const {
  return stage_->gnc_rounds() + stage_->final_rounds();
}

int GncAgent::gnc_rounds() const {
  return stage_->gnc_rounds();
}

int GncAgent::gnc_refine_steps() const {
  return stage_->gnc_refine_steps();
}

const Eigen::MatrixXd& GncAgent::last_pass_start() const {
  return stage_->last_pass_start();
}

const AgentState& GncAgent::state() const {
  return stage_->state();
}

const CertifiedAgent& GncAgent::last_solve() const {
  return stage_->solve();
}

const CertifiedAgent* GncAgent::final_sequence() const {
  return stage_->kind() == GncSolveKind::kFinal ? &stage_->solve() : nullptr;
}

const BlockLayout& GncAgent::layout() const {
  return stage_->layout();
}

const std::vector<Measurement>& GncAgent::kept_measurements() const {
  return stage_->kept();
}

const std::vector<std::uint64_t>& GncAgent::kept_index() const {
  return stage_->kept_index();
}

GncAgentResult GncAgent::result() const {
  GncAgentResult r;
  r.outer_iterations = outer_iterations();
  r.rejected.assign(rejected_.begin(), rejected_.end());
  r.readmitted = readmitted_;
  r.threshold_squared = threshold_squared();
  r.weights_converged = weights_converged();
  r.probes = probes();
  r.probes_kept = probes_kept();
  r.refine_message_steps = stage_->gnc_refine_steps();
  r.exchange_steps = exchange_steps_;
  r.solve_stages = stage_->gnc_solve_stages();
  return r;
}

int GncAgent::probes() const {
  return probes_->started();
}

int GncAgent::probes_kept() const {
  return probes_->kept();
}

}  // namespace tessera
