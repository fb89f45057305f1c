#pragma once
// A consistent point of one agent's round protocol, from which the run can be resumed with
// bit-identical iterates. Taken when round k's STATUS is about to be sent: Y^k and the
// neighbours' Y^k are known, nothing of round k has been exchanged yet. Every agent's snapshot
// of the same round k belongs to the same global state, so when *all* agents resume from
// round k (coordinated rollback) the run continues exactly as it would have.
//
// It holds everything that determines future iterates: the sequences of the own block and
// the neighbour copies (the *_prev ones too: an adaptive restart at round k goes back to
// round k-1), the previous round's reduction (f, ||grad||^2) and selection (redone on a
// restart), the momentum scheme's scalar recurrences, the restart counter and the trace.

#include <Eigen/Core>
#include <string>
#include <tessera/distributed/round_protocol.hpp>
#include <tessera/util/byte_codec.hpp>
#include <vector>

namespace tessera {

struct ProtocolSnapshot {
  int agent = 0;
  int round = 0;
  Eigen::MatrixXd Y, P, V, Y_prev, Yn, Pn, Vn, Yn_prev;
  std::vector<int> selection;
  double f_prev = 0.0, gsq_prev = 0.0;
  int restarts = 0;
  std::vector<double> scheme_state;  ///< MomentumScheme::save(); empty for RBCD.
  RoundHistory trace;  ///< Shares its older records with the protocol's and other snapshots'.
};

/// Appends every field of `s` to `out`; decode_snapshot reads them back bit-identical.
void encode(ByteWriter& out, const ProtocolSnapshot& s);
/// Throws CodecError when the bytes do not hold a snapshot.
ProtocolSnapshot decode_snapshot(ByteReader& in);

}  // namespace tessera
