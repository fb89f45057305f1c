#include <tessera/distributed/protocol_snapshot.hpp>

namespace tessera {

void encode(ByteWriter& out, const ProtocolSnapshot& s) {
  out.i64(s.agent);
  out.i64(s.round);
  for (const Eigen::MatrixXd* m : {&s.Y, &s.P, &s.V, &s.Y_prev, &s.Yn, &s.Pn, &s.Vn, &s.Yn_prev})
    out.matrix(*m);
  out.ints(s.selection);
  out.f64(s.f_prev);
  out.f64(s.gsq_prev);
  out.i64(s.restarts);
  out.doubles(s.scheme_state);
  out.u64(s.trace.size());
  for (std::size_t k = 0; k < s.trace.size(); ++k) {
    const RoundRecord& r = s.trace[k];
    out.i64(r.round);
    out.f64(r.cost);
    out.f64(r.grad_norm);
    out.ints(r.selected);
    out.boolean(r.restart);
    out.f64(r.elapsed_s);
  }
}

ProtocolSnapshot decode_snapshot(ByteReader& in) {
  ProtocolSnapshot s;
  s.agent = static_cast<int>(in.i64("snapshot agent"));
  s.round = static_cast<int>(in.i64("snapshot round"));
  s.Y = in.matrix("Y");
  s.P = in.matrix("P");
  s.V = in.matrix("V");
  s.Y_prev = in.matrix("Y_prev");
  s.Yn = in.matrix("Yn");
  s.Pn = in.matrix("Pn");
  s.Vn = in.matrix("Vn");
  s.Yn_prev = in.matrix("Yn_prev");
  s.selection = in.ints("selection");
  s.f_prev = in.f64("f_prev");
  s.gsq_prev = in.f64("gsq_prev");
  s.restarts = static_cast<int>(in.i64("restarts"));
  s.scheme_state = in.doubles("momentum state");
  const std::uint64_t n = in.u64("trace length");
  for (std::uint64_t k = 0; k < n; ++k) {
    RoundRecord r;
    r.round = static_cast<int>(in.i64("trace round"));
    r.cost = in.f64("trace cost");
    r.grad_norm = in.f64("trace grad norm");
    r.selected = in.ints("trace selection");
    r.restart = in.boolean("trace restart");
    r.elapsed_s = in.f64("trace elapsed");
    s.trace.push_back(std::move(r));
  }
  if (s.round < 0 || s.agent < 0) throw CodecError("snapshot: negative round or agent id");
  return s;
}

}  // namespace tessera
