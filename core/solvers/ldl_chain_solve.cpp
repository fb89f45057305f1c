#include "solvers/ldl_chain_solve.hpp"

namespace tessera {
namespace {

// The row updates of a forward chain over one run: x[k] -= a[k] y0 (+ b[k] y1 (+ c[k] y2)),
// the sum formed left to right as CHOLMOD forms it. Element-wise, so vectorising keeps the bits.
void forward_run(double* __restrict x, const double* __restrict a, double y0, int length) {
  for (int k = 0; k < length; ++k) x[k] -= a[k] * y0;
}
void forward_run(double* __restrict x, const double* __restrict a, const double* __restrict b,
                 double y0, double y1, int length) {
  for (int k = 0; k < length; ++k) x[k] -= a[k] * y0 + b[k] * y1;
}
void forward_run(double* __restrict x, const double* __restrict a, const double* __restrict b,
                 const double* __restrict c, double y0, double y1, double y2, int length) {
  for (int k = 0; k < length; ++k) x[k] -= a[k] * y0 + b[k] * y1 + c[k] * y2;
}

}  // namespace

void LdlChainSolve::clear() {
  forward_.clear();
  backward_.clear();
  forward_runs_.clear();
  backward_runs_.clear();
  ready_ = false;
}

void LdlChainSolve::add_runs(const int* rows, int count, std::vector<Run>& runs) {
  for (int t = 0; t < count;) {
    int length = 1;
    while (t + length < count && rows[t + length] == rows[t] + length) ++length;
    runs.push_back({rows[t], length});
    t += length;
  }
}

bool LdlChainSolve::build(const cholmod_factor* L) {
  clear();
  if (L == nullptr || L->is_super || L->is_ll || L->xtype != CHOLMOD_REAL ||
      L->itype != CHOLMOD_INT || L->dtype != CHOLMOD_DOUBLE || L->x == nullptr)
    return false;
  const int n = static_cast<int>(L->n);
  const auto* Lp = static_cast<const int*>(L->p);
  const auto* Li = static_cast<const int*>(L->i);
  const auto* Lnz = static_cast<const int*>(L->nz);
  // CHOLMOD's forward chain test (j, j+1, j+2 share their rows below the chain).
  for (int j = 0; j < n;) {
    const int p = Lp[j], lnz = Lnz[j];
    int width = 3;
    if (lnz < 4 || lnz != Lnz[j + 1] + 1 || Li[p + 1] != j + 1)
      width = 1;
    else if (lnz != Lnz[j + 2] + 2 || Li[p + 2] != j + 2)
      width = 2;
    const int begin = static_cast<int>(forward_runs_.size());
    add_runs(Li + p + width, lnz - width, forward_runs_);
    forward_.push_back({j, width, begin, static_cast<int>(forward_runs_.size())});
    j += width;
  }
  // Its backward chain test (j, j-1, j-2), from the last column.
  for (int j = n - 1; j >= 0;) {
    const int p = Lp[j], lnz = Lnz[j];
    int width = 3;
    if (j < 4 || lnz != Lnz[j - 1] - 1 || Li[Lp[j - 1] + 1] != j)
      width = 1;
    else if (lnz != Lnz[j - 2] - 2 || Li[Lp[j - 2] + 2] != j)
      width = 2;
    const int begin = static_cast<int>(backward_runs_.size());
    add_runs(Li + p + 1, lnz - 1, backward_runs_);
    backward_.push_back({j, width, begin, static_cast<int>(backward_runs_.size())});
    j -= width;
  }
  y_.assign(static_cast<std::size_t>(n), 0.0);
  ready_ = true;
  return true;
}

void LdlChainSolve::solve(const cholmod_factor* L, const double* rhs, double* out) const {
  const int n = static_cast<int>(L->n);
  const auto* Lp = static_cast<const int*>(L->p);
  const auto* Lx = static_cast<const double*>(L->x);
  const auto* perm = static_cast<const int*>(L->Perm);
  double* X = y_.data();
  for (int k = 0; k < n; ++k) X[k] = rhs[perm ? perm[k] : k];

  // L y = P b (unit diagonal).
  for (const Chain& ch : forward_) {
    const int j = ch.column, p = Lp[j];
    const Run* run = forward_runs_.data() + ch.run_begin;
    const Run* end = forward_runs_.data() + ch.run_end;
    if (ch.width == 1) {
      const double y0 = X[j];
      const double* a = Lx + p + 1;
      for (; run != end; a += run->length, ++run) forward_run(X + run->row, a, y0, run->length);
    } else if (ch.width == 2) {
      const int q = Lp[j + 1];
      const double y0 = X[j];
      const double y1 = X[j + 1] - Lx[p + 1] * y0;
      X[j + 1] = y1;
      const double* a = Lx + p + 2;
      const double* b = Lx + q + 1;
      for (; run != end; a += run->length, b += run->length, ++run)
        forward_run(X + run->row, a, b, y0, y1, run->length);
    } else {
      const int q = Lp[j + 1], r = Lp[j + 2];
      const double y0 = X[j];
      const double y1 = X[j + 1] - Lx[p + 1] * y0;
      const double y2 = X[j + 2] - Lx[p + 2] * y0 - Lx[q + 1] * y1;
      X[j + 1] = y1;
      X[j + 2] = y2;
      const double* a = Lx + p + 3;
      const double* b = Lx + q + 2;
      const double* c = Lx + r + 1;
      for (; run != end; a += run->length, b += run->length, c += run->length, ++run)
        forward_run(X + run->row, a, b, c, y0, y1, y2, run->length);
    }
  }

  // D L^T x = y: each column divided by its D entry first, then its dot with the rows below
  // subtracted in the factor's row order.
  for (const Chain& ch : backward_) {
    const int j = ch.column, p = Lp[j];
    const Run* run = backward_runs_.data() + ch.run_begin;
    const Run* end = backward_runs_.data() + ch.run_end;
    const double* a = Lx + p + 1;
    if (ch.width == 1) {
      double y0 = X[j] / Lx[p];
      for (; run != end; ++run) {
        const double* x = X + run->row;
        for (int k = 0; k < run->length; ++k) y0 -= a[k] * x[k];
        a += run->length;
      }
      X[j] = y0;
    } else if (ch.width == 2) {
      const int q = Lp[j - 1];
      const double t = Lx[q + 1];
      double y0 = X[j] / Lx[p];
      double y1 = X[j - 1] / Lx[q];
      const double* b = Lx + q + 2;
      for (; run != end; ++run) {
        const double* x = X + run->row;
        for (int k = 0; k < run->length; ++k) {
          y0 -= a[k] * x[k];
          y1 -= b[k] * x[k];
        }
        a += run->length;
        b += run->length;
      }
      y1 -= t * y0;
      X[j] = y0;
      X[j - 1] = y1;
    } else {
      const int q = Lp[j - 1], r = Lp[j - 2];
      const double t0 = Lx[q + 1], t1 = Lx[r + 1], t2 = Lx[r + 2];
      double y0 = X[j] / Lx[p];
      double y1 = X[j - 1] / Lx[q];
      double y2 = X[j - 2] / Lx[r];
      const double* b = Lx + q + 2;
      const double* c = Lx + r + 3;
      for (; run != end; ++run) {
        const double* x = X + run->row;
        for (int k = 0; k < run->length; ++k) {
          y0 -= a[k] * x[k];
          y1 -= b[k] * x[k];
          y2 -= c[k] * x[k];
        }
        a += run->length;
        b += run->length;
        c += run->length;
      }
      y1 -= t0 * y0;
      y2 -= t2 * y0 + t1 * y1;
      X[j - 2] = y2;
      X[j - 1] = y1;
      X[j] = y0;
    }
  }
  for (int k = 0; k < n; ++k) out[perm ? perm[k] : k] = X[k];
}

}  // namespace tessera
