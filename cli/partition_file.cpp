#include "partition_file.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <tessera/util/input_error.hpp>

namespace tessera::cli {

// "b0\nb1\n..." or JSON {..., "assignment": [b0, b1, ...]}.
std::vector<int> read_partition(const std::string& path, std::size_t n) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the partition file");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const auto key = text.find("\"assignment\"");
  if (key != std::string::npos) {
    const auto open = text.find('[', key), close = text.find(']', key);
    if (open == std::string::npos || close == std::string::npos)
      throw InputError(path, 0, "\"assignment\" is not an array");
    text = text.substr(open + 1, close - open - 1);
    for (char& c : text)
      if (c == ',') c = '\n';
  }
  std::vector<int> blocks;
  std::istringstream lines(text);
  std::string line;
  std::size_t number = 0;
  while (std::getline(lines, line)) {
    ++number;
    std::istringstream ls(line);
    std::string tok;
    if (!(ls >> tok) || tok[0] == '#') continue;
    char* end = nullptr;
    const long b = std::strtol(tok.c_str(), &end, 10);
    if (*end != '\0' || b < 0)
      throw InputError(path, key == std::string::npos ? number : 0,
                       "block '" + tok + "' is not a non-negative integer");
    blocks.push_back(static_cast<int>(b));
  }
  if (blocks.size() != n)
    throw InputError(
        path, 0,
        std::to_string(blocks.size()) + " blocks for a graph of " + std::to_string(n) + " poses");
  return blocks;
}

}  // namespace tessera::cli
