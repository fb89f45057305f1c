// The binary codec under every checkpoint and protocol snapshot: what is written is read back
// exactly, and a short or inconsistent buffer is a CodecError naming the buffer and the field
// that could not be read, never a crash or a huge allocation.

#include <gtest/gtest.h>

#include <string>
#include <tessera/util/byte_codec.hpp>
#include <vector>

namespace tessera {
namespace {

// The message of the CodecError `read` throws ("" when it throws none).
template <typename Read>
std::string codec_error_of(Read read) {
  try {
    read();
  } catch (const CodecError& e) {
    return e.what();
  }
  return "";
}

TEST(ByteCodec, EveryFieldTypeRoundTrips) {
  Eigen::MatrixXd m(2, 3);
  m << 1.5, -2.25, 3e-300, 4e300, -0.0, 6.0;
  ByteWriter w;
  w.u32(0xdeadbeefu);
  w.u64(1ull << 63);
  w.i64(-42);
  w.f64(-1.0 / 3.0);
  w.boolean(true);
  w.boolean(false);
  w.string(std::string("run\0id", 6));
  w.doubles({0.5, -7.0});
  w.u32s({1, 2, 4000000000u});
  w.u64s({});
  w.ints({-1, 0, 2147483647});
  w.matrix(m);
  w.matrix(Eigen::MatrixXd(0, 4));

  ByteReader r(w.bytes(), "buffer");
  EXPECT_EQ(r.u32("a"), 0xdeadbeefu);
  EXPECT_EQ(r.u64("b"), 1ull << 63);
  EXPECT_EQ(r.i64("c"), -42);
  EXPECT_EQ(r.f64("d"), -1.0 / 3.0);
  EXPECT_TRUE(r.boolean("e"));
  EXPECT_FALSE(r.boolean("f"));
  EXPECT_EQ(r.string("g"), std::string("run\0id", 6));
  EXPECT_EQ(r.doubles("h"), (std::vector<double>{0.5, -7.0}));
  EXPECT_EQ(r.u32s("i"), (std::vector<std::uint32_t>{1, 2, 4000000000u}));
  EXPECT_TRUE(r.u64s("j").empty());
  EXPECT_EQ(r.ints("k"), (std::vector<int>{-1, 0, 2147483647}));
  EXPECT_FALSE(r.at_end());
  const Eigen::MatrixXd back = r.matrix("l");
  ASSERT_EQ(back.rows(), 2);
  ASSERT_EQ(back.cols(), 3);
  EXPECT_EQ(back, m);  // bit-exact: resumed runs must continue with identical iterates
  const Eigen::MatrixXd empty = r.matrix("m");
  EXPECT_EQ(empty.rows(), 0);
  EXPECT_EQ(empty.cols(), 4);
  EXPECT_TRUE(r.at_end());
  EXPECT_NO_THROW(r.expect_end());
}

TEST(ByteCodec, TruncatedInputNamesTheBufferAndTheMissingField) {
  ByteWriter w;
  w.u32(7);
  w.f64(2.5);
  const std::string cut = w.bytes().substr(0, w.bytes().size() - 3);
  ByteReader r(cut, "agent-3.ckpt");
  EXPECT_EQ(r.u32("payload tag"), 7u);
  const std::string msg = codec_error_of([&] { r.f64("grad norm tolerance"); });
  EXPECT_NE(msg.find("agent-3.ckpt"), std::string::npos) << msg;
  EXPECT_NE(msg.find("truncated while reading grad norm tolerance"), std::string::npos) << msg;
  EXPECT_NE(msg.find("needs 8 bytes at offset 4, 5 left"), std::string::npos) << msg;
}

TEST(ByteCodec, ACountLargerThanTheBytesLeftIsAnErrorNotAnAllocation) {
  ByteWriter w;
  w.u64(1ull << 60);  // claims 2^60 doubles, none follow
  ByteReader r(w.bytes(), "buffer");
  const std::string msg = codec_error_of([&] { r.doubles("momentum state"); });
  EXPECT_NE(msg.find("momentum state claims"), std::string::npos) << msg;

  ByteWriter s;
  s.u64(5);
  s.u32(0);  // a 5-byte string with 4 bytes behind its length
  ByteReader rs(s.bytes(), "buffer");
  EXPECT_NE(codec_error_of([&] { rs.string("run id"); }).find("run id claims 5 elements"),
            std::string::npos);

  ByteWriter m;
  m.u64(1ull << 40);
  m.u64(1ull << 40);
  ByteReader rm(m.bytes(), "buffer");
  EXPECT_NE(codec_error_of([&] { rm.matrix("Y"); }).find("Y claims a"), std::string::npos);
}

TEST(ByteCodec, ABooleanMustBeZeroOrOne) {
  ByteWriter w;
  w.u32(2);
  ByteReader r(w.bytes(), "buffer");
  EXPECT_NE(codec_error_of([&] { r.boolean("restart"); }).find("restart is not a boolean"),
            std::string::npos);
}

TEST(ByteCodec, TrailingBytesAreAFormatMismatch) {
  ByteWriter w;
  w.u32(1);
  w.u32(2);
  ByteReader r(w.bytes(), "buffer");
  r.u32("first");
  EXPECT_NE(codec_error_of([&] { r.expect_end(); }).find("4 unexpected bytes after the last field"),
            std::string::npos);
  r.u32("second");
  EXPECT_NO_THROW(r.expect_end());
}

}  // namespace
}  // namespace tessera
