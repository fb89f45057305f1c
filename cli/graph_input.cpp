#include "graph_input.hpp"

#include <cstdio>
#include <tessera/io/stamps_reader.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera::cli {

const char* const kGraphInputOptions[] = {"keys", "stamps", nullptr};

const char* const kGraphInputHelp =
    "  --keys auto|plain|gtsam   how pose ids name robots: gtsam = the robot's character in\n"
    "                            the top byte ('a' << 56 | index, as GTSAM-based multi-robot\n"
    "                            systems write), plain = one robot; auto (default) detects\n"
    "                            gtsam keys and says so\n"
    "  --stamps FILE             timestamps of the poses: lines 'id stamp', or a TUM file\n"
    "                            matched by order (k-th line = k-th pose in id order)\n";

std::optional<KeyScheme> parse_keys_option(const std::string& name) {
  if (name == "auto") return std::nullopt;
  if (name == "plain") return KeyScheme::kPlain;
  if (name == "gtsam") return KeyScheme::kGtsam;
  throw InputError("option --keys: '" + name + "' is not one of auto, plain, gtsam");
}

G2oReadResult read_graph_input(const Arguments& a, const std::string& path, G2oReadOptions read) {
  read.keys = parse_keys_option(a.get_or("keys", "auto"));
  G2oReadResult r = read_g2o_file(path, read);
  if (!r.stats.keys_detected.empty())
    std::fprintf(stderr, "%s: %s\n", path.c_str(), r.stats.keys_detected.c_str());
  if (auto stamps = a.get("stamps")) r.keys.stamps = read_stamps_file(*stamps, r.graph, r.keys);
  return r;
}

}  // namespace tessera::cli
