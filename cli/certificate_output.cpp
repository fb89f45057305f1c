#include "certificate_output.hpp"

#include <cmath>
#include <cstdio>

namespace tessera::cli {

void add_certificate_bound(JsonObject& j, const DualBound& b, double rounded_cost) {
  j.add("certificate_method", std::string(certificate_method_name(b.method)))
      .add("dual_lower_bound", b.lower_bound)
      .add("suboptimality_bound", b.suboptimality(rounded_cost))
      .add("relative_suboptimality_bound", b.relative_suboptimality(rounded_cost))
      .add("relaxation_suboptimality_bound", b.suboptimality(b.relaxation_cost))
      .add("certificate_grad_norm", b.gradient_norm)
      .add("certificate_shift", b.shift);
}

std::string certificate_bound_line(const DualBound& b, double rounded_cost) {
  char buf[320];
  if (b.proved())
    std::snprintf(buf, sizeof buf,
                  "  lower bound on the optimum %.10g (proved at shift %.3g): the estimate is at "
                  "most %.3g (%.3g relative) above it; |grad f| = %.3g at the certified point\n",
                  b.lower_bound, b.shift, b.suboptimality(rounded_cost),
                  b.relative_suboptimality(rounded_cost), b.gradient_norm);
  else if (b.method == CertificateMethod::kLobpcg)
    std::snprintf(buf, sizeof buf,
                  "  LOBPCG's estimate (no interface test): no lower bound proved; |grad f| = "
                  "%.3g at the certified point\n",
                  b.gradient_norm);
  else if (std::isfinite(b.relaxation_cost))
    std::snprintf(buf, sizeof buf,
                  "  no lower bound on the optimum proved (no factorization of S + D "
                  "succeeded); |grad f| = %.3g at the certified point\n",
                  b.gradient_norm);
  else
    return {};
  return buf;
}

}  // namespace tessera::cli
