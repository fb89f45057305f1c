#include <tessera/io/text_file_writer.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"
#include "io/tum_line.hpp"

namespace tessera {

void write_tum(const std::vector<Pose>& poses, const std::string& path) {
  write_tum(poses, PoseKeys{}, path);
}

void write_tum(const std::vector<Pose>& poses, const PoseKeys& keys, const std::string& path) {
  const bool stamped = keys.stamps.size() == poses.size() && !poses.empty();
  for (const auto& p : poses)
    if ((p.dim() != 2 && p.dim() != 3) || p.R.rows() != p.dim() || p.R.cols() != p.dim())
      throw InputError(path, 0, "cannot write a pose of dimension " + std::to_string(p.dim()));

  TextFileWriter file(path);
  std::string& out = file.buffer();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Pose& p = poses[k];
    if (stamped)
      append_number(out, keys.stamps[k]);
    else
      append_integer(out, keys.id(k));
    append_tum_pose(out, p);
    file.maybe_flush();
  }
  file.close();
}

}  // namespace tessera
