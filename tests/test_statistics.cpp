// ctest-labels: unit
// The one percentile (core/statistics: linear interpolation between the closest ranks, numpy's
// default) and the one number formatter (core/format).
#include <phri/core/format.hpp>
#include <phri/core/statistics.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace {

TEST(Percentile, InterpolatesBetweenTheClosestRanksAsNumpyDoes) {
  const std::vector<double> v = {4.0, 1.0, 3.0, 2.0};  // sorted: 1 2 3 4
  EXPECT_DOUBLE_EQ(phri::percentile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(phri::percentile(v, 1.0), 4.0);
  EXPECT_DOUBLE_EQ(phri::percentile(v, 0.5), 2.5);          // mean of the middle two
  EXPECT_DOUBLE_EQ(phri::percentile(v, 0.95), 3.85);        // numpy.percentile([1,2,3,4], 95)
  EXPECT_DOUBLE_EQ(phri::percentile(v, 1.0 / 3.0), 2.0);    // on a rank exactly
  EXPECT_DOUBLE_EQ(phri::percentile({7.0, 1.0, 5.0}, 0.5), 5.0);
}

TEST(Percentile, ClampsPAndIsZeroWhenEmpty) {
  EXPECT_DOUBLE_EQ(phri::percentile({}, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(phri::percentile({3.0}, 0.99), 3.0);
  EXPECT_DOUBLE_EQ(phri::percentile({1.0, 2.0}, -1.0), 1.0);
  EXPECT_DOUBLE_EQ(phri::percentile({1.0, 2.0}, 2.0), 2.0);
}

TEST(Rms, OfValues) {
  EXPECT_DOUBLE_EQ(phri::rms({}), 0.0);
  EXPECT_DOUBLE_EQ(phri::rms({3.0, -4.0}), std::sqrt(12.5));
}

TEST(Format, FixedAndGeneralMatchPrintfAndTheStreams) {
  EXPECT_EQ(phri::format_fixed(3.14159, 2), "3.14");
  EXPECT_EQ(phri::format_fixed(-0.5, 0), "-0");
  EXPECT_EQ(phri::format_fixed(8.0, 6), std::to_string(8.0));
  EXPECT_EQ(phri::format_fixed(1e300, 2).size(), 304u);  // longer than any fixed buffer
  for (double x : {0.1, 1234567.0, 1e-7, -2.5}) {
    std::ostringstream s;
    s << x;
    EXPECT_EQ(phri::format_general(x, 6), s.str());
  }
  EXPECT_EQ(phri::format_general(0.125, 10), "0.125");
}

}  // namespace

namespace {
TEST(Format, ParseNumberTakesTheWholeTextOrNothing) {
  EXPECT_EQ(phri::parse_number("3.5"), 3.5);
  EXPECT_EQ(phri::parse_number("-1e-3"), -1e-3);
  EXPECT_TRUE(std::isinf(*phri::parse_number("inf")));  // the caller decides about these
  EXPECT_TRUE(std::isnan(*phri::parse_number("nan")));
  for (const char* bad : {"", "abc", "3.5s", "1e400", "0.01@3", " "}) EXPECT_FALSE(phri::parse_number(bad)) << bad;
}
}  // namespace
