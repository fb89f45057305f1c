#pragma once
// The certificate's iteration cap of the commands' distributed runs (`tessera solve` with a
// distributed algorithm, `tessera launch`'s agents), above DistributedCertificateOptions's
// default of 300. Why: block Jacobi needs more LOBPCG iterations the more measurements the
// partition cuts, and robot-aligned blocks cut many: city10000 at 5 agents needs 720 on
// contiguous id ranges (cut 8,369) against 149 on the eco partition (cut 160)
// (docs/distributed-certification.md). The cap only costs iterations where a certificate would
// otherwise stop unconverged ("inconclusive").

namespace tessera {

inline constexpr int kCommandCertificateIterations = 1000;

}  // namespace tessera
