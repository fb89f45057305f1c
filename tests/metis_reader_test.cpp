// The METIS reader: the format as the benchmark files use it, and every malformed-input error.

#include <gtest/gtest.h>

#include <string>
#include <tessera/io/metis_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "test_support.hpp"

namespace {

using tessera::InputError;
using tessera::read_metis;

std::string metis_file(const std::string& name, const std::string& text) {
  return tessera::test::write_file(tessera::test::temp_dir(), name, text);
}

// Reads the file and returns the error message ("" if it was accepted).
std::string error_of(const std::string& text) {
  try {
    read_metis(metis_file("bad.graph", text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::size_t weight_between(const tessera::GraphStructure& g, std::size_t u, std::size_t v) {
  for (std::size_t e = g.offsets[u]; e < g.offsets[u + 1]; ++e)
    if (g.neighbors[e] == v) return g.weights[e];
  return 0;
}

TEST(MetisReader, ReadsTriangleWithRepeatedEntriesAsWeights) {
  // 1-2 twice (parallel measurements), 2-3 once, 1-3 once: m counts records (4).
  const auto g = read_metis(metis_file("tri.graph", "% a comment\n3 4\n2 2 3\n1 1 3\n1 2\n"));
  EXPECT_EQ(g.num_vertices, 3u);
  EXPECT_EQ(g.num_pairs(), 3u);
  EXPECT_EQ(g.total_edge_weight(), 4u);
  EXPECT_EQ(weight_between(g, 0, 1), 2u);
  EXPECT_EQ(weight_between(g, 1, 0), 2u);
  EXPECT_EQ(weight_between(g, 1, 2), 1u);
  EXPECT_EQ(weight_between(g, 0, 2), 1u);
}

TEST(MetisReader, EdgeWeightsAndIsolatedVertex) {
  // fmt 1: neighbour, weight pairs; vertex 3 has an empty line (isolated).
  const auto g = read_metis(metis_file("w.graph", "3 1 1\n2 5\n1 5\n\n"));
  EXPECT_EQ(g.num_vertices, 3u);
  EXPECT_EQ(g.total_edge_weight(), 5u);
  EXPECT_EQ(g.degree(2), 0u);
}

TEST(MetisReader, UnitVertexWeightsAccepted) {
  const auto g = read_metis(metis_file("vw.graph", "2 1 10\n1 2\n1 1\n"));
  EXPECT_EQ(g.num_pairs(), 1u);
}

TEST(MetisReader, WrongHeaderIsAnError) {
  EXPECT_NE(error_of("").find("empty file"), std::string::npos);
  EXPECT_NE(error_of("3\n2\n1 3\n2\n").find("bad METIS header"), std::string::npos);
  EXPECT_NE(error_of("three 2\n2\n1 3\n2\n").find("bad METIS header"), std::string::npos);
  EXPECT_NE(error_of("3 2 0 1 7\n2\n1 3\n2\n").find("bad METIS header"), std::string::npos);
  EXPECT_NE(error_of("3 2 5\n2\n1 3\n2\n").find("unsupported METIS fmt"), std::string::npos);
  EXPECT_NE(error_of("3 2 0 2\n2\n1 3\n2\n").find("ncon"), std::string::npos);
  const std::string msg = error_of("3 x\n2\n1 3\n2\n");
  EXPECT_NE(msg.find("bad.graph:1:"), std::string::npos) << msg;
}

TEST(MetisReader, VertexIdOutOfRangeNamesTheLine) {
  const std::string msg = error_of("3 2\n2\n1 4\n2\n");
  EXPECT_NE(msg.find("bad.graph:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("vertex id 4 out of range 1..3"), std::string::npos) << msg;
  EXPECT_NE(error_of("3 2\n2\n0 3\n2\n").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("3 2\n2\n1 -3\n2\n").find("not a vertex id"), std::string::npos);
}

TEST(MetisReader, StructuralErrors) {
  EXPECT_NE(error_of("2 1\n1\n2\n").find("self loop"), std::string::npos);
  EXPECT_NE(error_of("3 2\n2\n1 3\n1\n").find("asymmetric adjacency"), std::string::npos);
  EXPECT_NE(error_of("3 3\n2\n1 3\n2\n").find("header announces 3 edges"), std::string::npos);
  EXPECT_NE(error_of("3 2\n2\n1 3\n").find("file ends after 2 vertex lines"), std::string::npos);
  EXPECT_NE(error_of("3 2\n2\n1 3\n2\n1\n").find("more vertex lines"), std::string::npos);
  EXPECT_NE(error_of("2 1 1\n2\n1 1\n").find("without an edge weight"), std::string::npos);
  EXPECT_NE(error_of("2 1 1\n2 0\n1 0\n").find("positive integer"), std::string::npos);
  EXPECT_NE(error_of("2 1 10\n3 2\n1 1\n").find("only unit vertex weights"), std::string::npos);
  EXPECT_THROW(read_metis("/nonexistent/file.graph"), InputError);
}

TEST(MetisReader, DetectsFormatByContent) {
  EXPECT_TRUE(tessera::looks_like_metis(metis_file("a.txt", "% c\n\n3 2\n2\n1 3\n2\n")));
  EXPECT_FALSE(tessera::looks_like_metis(metis_file("b.txt", "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n")));
  EXPECT_FALSE(tessera::looks_like_metis(metis_file("c.txt", "")));
}

TEST(MetisReader, BenchmarkRimGraph) {
  TESSERA_REQUIRE_SHARED();
  const auto g = read_metis(tessera::test::shared_dir() + "/datasets/metis/rim.graph");
  EXPECT_EQ(g.num_vertices, 10195u);
  EXPECT_EQ(g.total_edge_weight(), 29743u);  // edge records, parallel ones included
  EXPECT_EQ(g.num_pairs(), 22251u);          // distinct pairs (MANIFEST.md)
}

}  // namespace
