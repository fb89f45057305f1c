#pragma once
// The inlier passes' bookkeeping in the distributed GNC: how many passes were judged against
// RobustOptions::readmission_passes, whether the running pass is capped at
// RobustOptions::recheck_max_rounds or solved to the tolerance, and whether it starts from a
// pass solved to the tolerance (which lets an unchanged verdict on a capped pass stand,
// RobustOptions::recheck_confirm_solved). GncAgent decides when a pass opens, ends or is judged;
// this holds what those events leave for the next decision. Every agent holds the same: the
// events follow the summed votes and verdicts.

#include <tessera/robust/robust_options.hpp>

namespace tessera {

class GncInlierPasses {
 public:
  /// `options` must outlive this.
  explicit GncInlierPasses(const RobustOptions& options) : options_(options) {}

  /// A pass opens; `refines`: its solve hands over to the Newton refinement. Such a pass is
  /// solved to the tolerance even while its set may still change: from the last iterate that
  /// costs fewer message steps than the capped rounds.
  void open(bool refines) {
    capped_ = options_.recheck_max_rounds > 0 && !full_next_ && !refines;
    full_next_ = false;
    from_solved_ = last_full_;
    last_full_ = false;
  }
  /// The running (or last) pass stops at RobustOptions::recheck_max_rounds.
  bool capped() const { return capped_; }
  /// The running pass's solve ended.
  void solved() { last_full_ = !capped_; }
  /// A re-check verdict judged the pass that ended.
  void judged() { ++judged_; }
  /// The passes judged so far used up RobustOptions::readmission_passes.
  bool budget_spent() const { return judged_ >= options_.readmission_passes; }
  /// The next pass is solved to the tolerance.
  void solve_next_fully() { full_next_ = true; }
  /// The next pass does not count as starting from a solved pass (after a vote on the kept
  /// set's fresh start, whichever won, and after a probe's flips).
  void forget_solved_start() { last_full_ = false; }
  /// The passes again, with their own budget.
  void restart_budget() { judged_ = 0; }
  /// One last pass, solved to the tolerance, and no verdict after it opens another.
  void last_full_pass() {
    judged_ = options_.readmission_passes;
    full_next_ = true;
  }
  /// A verdict that changed nothing on the running pass still needs the same set solved to the
  /// tolerance: the pass was capped, and it did not start from a solved pass whose verdict a
  /// final solve (`final_solve_runs`) would confirm anyway (it only settled that pass's flips).
  bool unchanged_needs_full_pass(bool final_solve_runs) const {
    const bool confirmed = options_.recheck_confirm_solved && from_solved_ && final_solve_runs;
    return capped_ && !confirmed;
  }

 private:
  const RobustOptions& options_;
  int judged_ = 0;            // passes judged by a re-check verdict
  bool capped_ = false;       // the current pass stops at RobustOptions::recheck_max_rounds
  bool full_next_ = false;    // the next pass is solved to the tolerance
  bool last_full_ = false;    // the last pass that ended was solved to the tolerance
  bool from_solved_ = false;  // the current pass starts from a pass solved to the tolerance
};

}  // namespace tessera
