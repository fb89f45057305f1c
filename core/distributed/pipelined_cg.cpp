#include "distributed/pipelined_cg.hpp"

#include <algorithm>

namespace tessera {

void PipelinedCg::restart() {
  iterations_ = 0;
  e_Pe_ = e_Pd_ = d_Pd_ = 0.0;
}

PipelinedCgIteration PipelinedCg::begin(double gamma, double delta) {
  PipelinedCgIteration it;
  it.first = iterations_ == 0;
  it.gamma = gamma;
  // Chronopoulos-Gear: beta from <r, z>; <p, H p> from <z, H z> and the recurrences.
  it.beta = it.first ? 0.0 : gamma / gamma_old_;
  it.pHp = it.first ? delta : delta - it.beta * gamma / alpha_old_;
  it.alpha = gamma / it.pHp;
  ++iterations_;
  return it;
}

void PipelinedCg::end(const PipelinedCgIteration& it) {
  gamma_old_ = it.gamma;
  alpha_old_ = it.alpha;
}

void PipelinedCg::update_norms(const PipelinedCgIteration& it) {
  if (it.first) {
    d_Pd_ = it.gamma;
    e_Pd_ = 0.0;
  } else {
    e_Pd_ = it.beta * (e_Pd_ + alpha_old_ * d_Pd_);
    d_Pd_ = it.gamma + it.beta * it.beta * d_Pd_;
  }
}

double PipelinedCg::step_norm2_after(const PipelinedCgIteration& it) const {
  return e_Pe_ + 2 * it.alpha * e_Pd_ + it.alpha * it.alpha * d_Pd_;
}

double PipelinedCg::boundary_step(double radius2) const {
  return (-e_Pd_ + std::sqrt(std::max(0.0, e_Pd_ * e_Pd_ + d_Pd_ * (radius2 - e_Pe_)))) / d_Pd_;
}

double PipelinedCg::next_residual_norm2(const PipelinedCgIteration& it, double rr, double rw,
                                        double ww, double rq, double wq, double qq) {
  const double rq_new = rw + it.beta * rq;
  const double qq_new = ww + 2.0 * it.beta * wq + it.beta * it.beta * qq;
  return rr - 2.0 * it.alpha * rq_new + it.alpha * it.alpha * qq_new;
}

}  // namespace tessera
