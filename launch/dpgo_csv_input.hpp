#pragma once
// `tessera launch` on a dpgo measurement CSV (one file, or a folder of robot<k>/measurements.csv;
// core/include/tessera/io/dpgo_csv_reader.hpp): the agents read g2o, so launch turns the CSV
// into one g2o file per robot (runtime/robot_file.hpp's convention), robot k owning the ids of
// the CSV's robot k. The CSV's is_known_inlier column goes to each robot file's
// '# tessera-known-inliers' line; the agents announce their flags and the coordinator's
// assignment gives every agent the whole set (each needs all of them: c^2's default counts the
// measurements that may be rejected, and the known inliers' start uses every flagged one).

#include <string>

namespace tessera::launch {

/// When `graph` is a dpgo CSV: writes DIR/robot<k>.g2o for each of its robots and returns DIR
/// (created under `work`); `agents` must equal the number of robots (InputError naming both
/// otherwise). Returns "" for any other input. Bad rows: InputError "file:line: what".
std::string dpgo_csv_as_robot_files(const std::string& graph, long agents, const std::string& work);

}  // namespace tessera::launch
