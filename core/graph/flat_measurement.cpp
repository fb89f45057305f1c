#include <stdexcept>
#include <string>
#include <tessera/graph/flat_measurement.hpp>

namespace tessera {

void append_measurement_rt(std::vector<double>& rotations, std::vector<double>& translations,
                           const Measurement& e) {
  // Eigen's default storage is column-major, which is the layout.
  rotations.insert(rotations.end(), e.R.data(), e.R.data() + e.R.size());
  translations.insert(translations.end(), e.t.data(), e.t.data() + e.t.size());
}

namespace {

void require_values(const std::vector<double>& data, std::size_t offset, std::size_t count,
                    const char* what) {
  if (offset > data.size() || data.size() - offset < count)
    throw std::out_of_range(std::string("flat measurement: ") + std::to_string(data.size()) +
                            " values end before the " + what + " at " + std::to_string(offset) +
                            " (" + std::to_string(count) + " values)");
}

}  // namespace

void read_measurement_rt(const std::vector<double>& rotations, std::size_t r_offset,
                         const std::vector<double>& translations, std::size_t t_offset, int d,
                         Measurement& e) {
  const std::size_t dd = static_cast<std::size_t>(d);
  require_values(rotations, r_offset, dd * dd, "rotation");
  require_values(translations, t_offset, dd, "translation");
  e.R = Eigen::Map<const Eigen::MatrixXd>(rotations.data() + r_offset, d, d);
  e.t = Eigen::Map<const Eigen::VectorXd>(translations.data() + t_offset, d);
}

}  // namespace tessera
