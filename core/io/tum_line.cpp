#include "io/tum_line.hpp"

#include "io/number_text.hpp"
#include "io/rotation_text.hpp"

namespace tessera {

void append_tum_pose(std::string& out, const Pose& p) {
  for (int c = 0; c < 3; ++c) {
    out += ' ';
    append_number(out, c < p.dim() ? p.t(c) : 0.0);
  }
  for (double q : unit_quaternion(p.R)) {
    out += ' ';
    append_number(out, q);
  }
  out += '\n';
}

}  // namespace tessera
