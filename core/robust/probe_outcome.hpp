#pragma once
// The verdict that ends a probe after the re-check passes, centralized (cluster_probes.cpp,
// swap_probe.cpp) and distributed (gnc_probes.hpp). A probe changes the rejected set (cuts kept
// measurements, brings rejected ones back), the passes run from there, and the probe stays only
// when the TLS cost over every measurement fell by more than the solves' accuracy: each kept
// probe is a descent step of the TLS cost, a refused one changes nothing.
//
// A probe whose passes put the set back where it started (what it cut came back, what it brought
// back was cut again) ends not kept, whatever the two TLS costs say: they belong to the same set
// solved twice and differ only by the solves' accuracy. Without this rule the distributed run on
// CSAIL with 25 % random outliers kept such a probe on a TLS cost 2.5e-5 lower (1,043.349530
// against 1,043.349555) and ran a second one: 1,320 rounds against 476, the same answer
// (docs/robust.md, "Probes").

#include <cmath>
#include <vector>

namespace tessera {

enum class ProbeOutcome {
  kKept,        ///< Another set, TLS cost lower beyond the accuracy: the probe stays.
  kRefused,     ///< Another set, TLS cost not lower: the set and iterate from before come back.
  kBackAtBase,  ///< The passes ended at the set the probe started from: not kept.
};

/// The outcome of a probe that started at `base_rejected` (ascending) with TLS cost `base_tls`
/// and whose passes ended at `trial_rejected` (ascending) with `trial_tls`. `accuracy` is the
/// relative margin below the base's cost that counts as lower (>= 0).
template <class Id>
ProbeOutcome probe_outcome(const std::vector<Id>& base_rejected, double base_tls,
                           const std::vector<Id>& trial_rejected, double trial_tls,
                           double accuracy) {
  if (trial_rejected == base_rejected) return ProbeOutcome::kBackAtBase;
  return trial_tls < base_tls - accuracy * std::abs(base_tls) ? ProbeOutcome::kKept
                                                              : ProbeOutcome::kRefused;
}

}  // namespace tessera
