#include "structure_graphs.hpp"

#include <utility>
#include <vector>

namespace tessera::test {

GraphStructure grid_structure(std::size_t w, std::size_t h) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t y = 0; y < h; ++y)
    for (std::size_t x = 0; x < w; ++x) {
      if (x + 1 < w) pairs.emplace_back(y * w + x, y * w + x + 1);
      if (y + 1 < h) pairs.emplace_back(y * w + x, (y + 1) * w + x);
    }
  return make_graph_structure(w * h, pairs, "grid");
}

}  // namespace tessera::test
