#include <tessera/robust/gnc_agent_result.hpp>

namespace tessera {

long long message_steps(const GncAgentResult& gnc, long long rounds, long long final_solve_stages,
                        long long final_refine_steps) {
  return 2 * rounds + 2 * (gnc.solve_stages + final_solve_stages) + gnc.refine_message_steps +
         final_refine_steps + gnc.exchange_steps;
}

}  // namespace tessera
