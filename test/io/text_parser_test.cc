#include "rff_ceres/io/text_parser.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <fstream>
#include <ios>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "test/test_files.h"

namespace rff {
namespace {

TEST(TextParserTest, ParsesFiniteNumbersWhole) {
  double v = 0.0;
  EXPECT_TRUE(ParseFiniteDouble("1.5e-3", &v));
  EXPECT_DOUBLE_EQ(v, 1.5e-3);
  EXPECT_TRUE(ParseFiniteDouble("-0", &v));
  EXPECT_EQ(v, 0.0);
  EXPECT_TRUE(std::signbit(v));
  EXPECT_TRUE(ParseFiniteDouble("1e-400", &v));  // Underflow is harmless.
  EXPECT_FALSE(ParseFiniteDouble("", &v));
  EXPECT_FALSE(ParseFiniteDouble("1.5x", &v));
  EXPECT_FALSE(ParseFiniteDouble("nan", &v));
  EXPECT_FALSE(ParseFiniteDouble("-inf", &v));
  EXPECT_FALSE(ParseFiniteDouble("1e999", &v));
  EXPECT_FALSE(ParseFiniteDouble(std::string(100, '1'), &v));
}

// Every text it takes is strtod's number, bit for bit, whichever reader
// took it: the fast one for plain decimals, strtod for the rest ('+',
// hexadecimal, underflow) and for what neither takes.
TEST(TextParserTest, ReadsWhatStrtodReads) {
  for (const char* text : {"1248444175.103",
                           "0.1",
                           "-2.5e-7",
                           "7",
                           ".5",
                           "5.",
                           "1E+3",
                           "+1.5",
                           "0x1p-3",
                           "1e-310",
                           "1e-400",
                           "-1e-400",
                           "4.9406564584124654e-324",
                           "1.7976931348623157e308",
                           "00012.50",
                           "1.5 ",
                           " 1.5",
                           "1,5",
                           "0x",
                           "+-1",
                           "--1",
                           "1e",
                           "e5",
                           "."}) {
    char* end = nullptr;
    const double expected = std::strtod(text, &end);
    const bool whole = *end == '\0' && end != text;
    double v = -123.0;
    EXPECT_EQ(ParseFiniteDouble(text, &v), whole && std::isfinite(expected))
        << text;
    if (whole) {
      EXPECT_EQ(v, expected) << text;
      EXPECT_EQ(std::signbit(v), std::signbit(expected)) << text;
    }
  }
}

TEST(TextParserTest, ParsesNonNegativeIntegers) {
  std::int64_t id = -1;
  EXPECT_TRUE(ParseNonNegativeInt("0", &id));
  EXPECT_EQ(id, 0);
  EXPECT_TRUE(ParseNonNegativeInt("9223372036854775807", &id));
  EXPECT_EQ(id, 9223372036854775807LL);
  EXPECT_FALSE(ParseNonNegativeInt("9223372036854775808", &id));
  EXPECT_FALSE(ParseNonNegativeInt("-1", &id));
  EXPECT_FALSE(ParseNonNegativeInt("+1", &id));
  EXPECT_FALSE(ParseNonNegativeInt("1e3", &id));
  EXPECT_FALSE(ParseNonNegativeInt("", &id));
}

TEST(TextParserTest, WrapsAnglesToHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(WrapAngle(M_PI), M_PI);
  EXPECT_DOUBLE_EQ(WrapAngle(-M_PI), M_PI);
  EXPECT_NEAR(WrapAngle(3.0 * M_PI / 2.0), -M_PI / 2.0, 1e-15);
  EXPECT_NEAR(WrapAngle(-7.0), -7.0 + 2.0 * M_PI, 1e-15);
  EXPECT_DOUBLE_EQ(WrapAngle(0.25), 0.25);
}

// WrapAngle's shortcuts return what remainder() does, bit for bit: angles
// in range, odd multiples of pi and their neighbours (where the quotient's
// rounding can miss the turn), random angles up to 1e9 rad and past the
// 2^40 where remainder() takes over.
TEST(TextParserTest, WrappedAnglesAreRemaindersBitForBit) {
  auto remainder_wrap = [](double a) {
    double wrapped = std::remainder(a, 2.0 * M_PI);
    if (wrapped <= -M_PI) wrapped += 2.0 * M_PI;
    return wrapped;
  };
  std::vector<double> angles = {-1e-300, 0.0, -0.0, 3.0, M_PI, -M_PI,
                                0x1p40, -0x1p40, 1e15, -1e300};
  for (double k = 1.0; k < 2e6; k = 2.0 * k + 1.0) {
    for (const double sign : {1.0, -1.0}) {
      double a = sign * k * M_PI;
      for (int step = 0; step < 4; ++step) a = std::nextafter(a, 0.0);
      for (int step = 0; step < 9; ++step) {
        angles.push_back(a);
        a = std::nextafter(a, sign * 1e300);
      }
    }
  }
  std::mt19937_64 random(5);
  for (const double scale : {10.0, 1e4, 1e9}) {
    std::uniform_real_distribution<double> uniform(-scale, scale);
    for (int i = 0; i < 20000; ++i) angles.push_back(uniform(random));
  }
  for (const double a : angles) {
    const double expected = remainder_wrap(a);
    const double wrapped = WrapAngle(a);
    ASSERT_EQ(std::memcmp(&wrapped, &expected, sizeof(double)), 0)
        << std::hexfloat << a << ": " << wrapped << " != " << expected;
  }
}

TEST(TextParserTest, FormatNumberRoundTrips) {
  for (const double v : {0.1 + 0.2, 1248444175.103, -1e-300, 0.0, 42.0}) {
    double back = 0.0;
    ASSERT_TRUE(ParseFiniteDouble(FormatNumber(v), &back));
    EXPECT_EQ(back, v);
  }
  EXPECT_EQ(FormatNumber(42.0), "42");
}

// A stream buffer whose reads fail after `good` characters, throwing as
// libstdc++'s filebuf does on an I/O error.
class FailingBuffer : public std::streambuf {
 public:
  explicit FailingBuffer(std::string good) : good_(std::move(good)) {
    setg(good_.data(), good_.data(), good_.data() + good_.size());
  }

 protected:
  int_type underflow() override {
    throw std::ios_base::failure("Input/output error");
  }

 private:
  std::string good_;
};

// A failed read is a read error, before or within a line: never a crash,
// and never the part of a line read before it.
TEST(TextParserTest, AFailedReadIsAReadError) {
  for (const std::string& good :
       {std::string(), std::string("a b\nc d"), std::string("a b\n")}) {
    FailingBuffer buffer(good);
    std::istream in(&buffer);
    LineReader reader(&in, "f.txt");
    std::vector<std::string_view> fields;
    if (good.find('\n') != std::string::npos) {
      ASSERT_TRUE(reader.Next(&fields));
      EXPECT_EQ(fields, (std::vector<std::string_view>{"a", "b"}));
    }
    EXPECT_FALSE(reader.Next(&fields)) << good;
    EXPECT_FALSE(reader.ok()) << good;
    EXPECT_EQ(reader.error(),
              good.empty() ? "f.txt:0: read error" : "f.txt:1: read error");
  }
}

// A named pipe is refused at once (opening it would wait for a writer);
// an anonymous one, a shell's <(...), is read to its end.
TEST(TextParserTest, ANamedPipeIsRefusedAnAnonymousOneRead) {
  const std::string fifo = testing::TempDir("TextParserTest") + "/named.pipe";
  ::unlink(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::ifstream stream;
  std::string error;
  EXPECT_FALSE(OpenForReading(fifo, &stream, &error));
  EXPECT_EQ(error, fifo +
                       ": cannot open for reading: is a named pipe, which "
                       "may wait forever for a writer; give a file, or the "
                       "pipe as <(cat " +
                       fifo + ")");
  int ends[2];
  ASSERT_EQ(::pipe(ends), 0);
  ASSERT_EQ(::write(ends[1], "a b\n", 4), 4);
  ::close(ends[1]);
  const std::string anonymous = "/dev/fd/" + std::to_string(ends[0]);
  ASSERT_TRUE(OpenForReading(anonymous, &stream, &error)) << error;
  LineReader reader(&stream, anonymous);
  std::vector<std::string_view> fields;
  ASSERT_TRUE(reader.Next(&fields));
  EXPECT_EQ(fields, (std::vector<std::string_view>{"a", "b"}));
  EXPECT_FALSE(reader.Next(&fields));
  EXPECT_TRUE(reader.ok()) << reader.error();
  ::close(ends[0]);
}

TEST(TextParserTest, SplitsFieldsSkipsCommentsAndCountsLines) {
  std::istringstream in("# key: value\n\n  a\tb  # c\r\n#x\nd\n");
  LineReader reader(&in, "f.txt");
  std::vector<std::string_view> fields;
  ASSERT_TRUE(reader.Next(&fields));
  ASSERT_EQ(fields.size(), 2u);
  EXPECT_EQ(fields[0], "a");
  EXPECT_EQ(fields[1], "b");
  EXPECT_EQ(reader.line_number(), 3);
  ASSERT_TRUE(reader.Next(&fields));
  EXPECT_EQ(fields[0], "d");
  EXPECT_EQ(reader.line_number(), 5);
  EXPECT_FALSE(reader.Next(&fields));
  EXPECT_TRUE(reader.ok());
  ASSERT_EQ(reader.leading_comments().size(), 1u);
  EXPECT_EQ(reader.leading_comments()[0], " key: value");
  EXPECT_EQ(reader.Error("bad"), "f.txt:5: bad");
}

}  // namespace
}  // namespace rff
