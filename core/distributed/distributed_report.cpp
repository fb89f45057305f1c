// DistributedResult::full_report(): the result of a distributed solve for people, in the
// manner of CentralizedResult::full_report().

#include <sstream>
#include <tessera/distributed/distributed_solver.hpp>

namespace tessera {

std::string DistributedResult::full_report() const {
  std::ostringstream os;
  os.precision(12);
  os << "Distributed solve, " << agents << " agents\n";
  os << "  " << rounds << " rounds (" << restarts << " restarts), stop: " << stop_reason
     << ", final rank " << final_rank << "\n";
  os << "  rounded cost " << cost << " (relaxation " << relaxation_cost << ", |grad| " << grad_norm
     << ")\n";
  os << "  certified: " << (certified ? (*certified ? "yes" : "no") : "not checked");
  if (certified)
    os << " (lambda_min(S) = " << min_eigenvalue << ", tolerance " << certificate_tolerance
       << ", residual " << certificate_residual << ", " << certificate_rounds
       << " LOBPCG iterations)";
  os << "\n";
  for (const auto& c : certificates)
    os << "    certificate at rank " << c.rank << ": "
       << (c.result.certified ? "certified" : "not certified") << ", lambda_min "
       << c.result.min_eigenvalue << ", " << c.result.iterations << " iterations\n";
  for (const auto& e : escapes)
    os << "    escape from rank " << e.rank << ": " << (e.success ? "done" : "failed") << " after "
       << e.trials << " trials, step " << e.alpha << ", cost " << e.cost << "\n";
  if (refine_rounds > 0 || escape_rounds > 0)
    os << "  staircase: " << refine_rounds << " refine rounds, " << escape_rounds
       << " escape trials\n";
  os << "  traffic: " << messages << " messages, " << bytes_exchanged << " bytes (certificate "
     << certificate_bytes << ", escape " << escape_bytes << ")\n";
  os << "  work: " << block_updates << " block updates, " << tcg_iterations
     << " truncated-CG iterations, " << tangent_updates << " tangent-preconditioned updates, "
     << tangent_factorizations << " factorizations\n";
  os << "  time: init " << init_s << " s, rounds " << solve_s << " s (CPU " << solve_cpu_s
     << " s, critical path " << critical_path_cpu_s << " s), rounding " << rounding_s
     << " s, total " << wall_s << " s\n";
  return os.str();
}

}  // namespace tessera
