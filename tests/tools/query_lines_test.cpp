// The parser of `umbra query`'s input lines (tools/query_lines.cpp) on the
// hostile lines its fuzz target also meets: NUL bytes and control characters
// (quoted as \xNN, long words cut in the message), a line of a million
// numbers (only the kind's count kept, the count said), numbers beyond
// double range, infinities and NaN in every spelling from_chars knows,
// separators mixed; lines read in order with their numbers, each before
// the next is written; lines over kMaxQueryLineBytes refused with their
// length (comments skipped) without ending the input; a stream that fails
// to read is an error, not an empty answer. Reference: the lines' values
// written by the test.
#include <gtest/gtest.h>

#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "query_lines.hpp"

namespace umbra::cli {
namespace {

std::string problem_of(std::string_view text, LineQuery kind) {
  std::vector<double> values;
  const auto problem = parse_query_line(text, kind, values);
  if (problem) {
    EXPECT_TRUE(values.empty()) << text;
  }
  return problem.value_or("");
}

TEST(QueryLines, KindsAndLayouts) {
  for (const char* name : {"sphere", "box", "line", "raycast", "gain"}) {
    const auto kind = line_query_named(name);
    ASSERT_TRUE(kind) << name;
    EXPECT_STREQ(to_string(*kind), name);
  }
  EXPECT_FALSE(line_query_named("cone"));
  EXPECT_FALSE(line_query_named(""));
  EXPECT_FALSE(line_query_named("nodes"));  // takes no lines
  EXPECT_EQ(numbers_of(LineQuery::sphere), 4u);
  EXPECT_EQ(numbers_of(LineQuery::box), 6u);
  EXPECT_EQ(numbers_of(LineQuery::line), 6u);
  EXPECT_EQ(numbers_of(LineQuery::raycast), 7u);
  EXPECT_EQ(numbers_of(LineQuery::gain), 5u);
  EXPECT_EQ(numbers_of(LineQuery::distance), 3u);
}

TEST(QueryLines, GoodLinesGiveTheirValues) {
  std::vector<double> values;
  EXPECT_FALSE(parse_query_line(" 1,-2.5\t3e2 ,, 0.25\r", LineQuery::sphere, values));
  EXPECT_EQ(values, (std::vector<double>{1, -2.5, 300, 0.25}));
  EXPECT_FALSE(parse_query_line("1e-320 0 0 0 0 0 1.7976931348623157e308", LineQuery::raycast, values));
  EXPECT_EQ(values.front(), 1e-320);  // subnormal, still a number
  EXPECT_EQ(values.back(), 1.7976931348623157e308);
  EXPECT_FALSE(parse_query_line("+1 +.5 -0 +2e1", LineQuery::sphere, values));
  EXPECT_EQ(values, (std::vector<double>{1, 0.5, 0, 20}));
}

TEST(QueryLines, BadNumbersAreNamed) {
  for (const char* word : {"nan", "NaN", "inf", "-inf", "infinity", "0x10", "1..2", "1e", "+-1", "--1", "++1", "+"}) {
    const std::string line = std::string("0 0 0 ") + word;
    EXPECT_EQ(problem_of(line, LineQuery::sphere), "'" + std::string(word) + "' is not a finite number") << line;
  }
  for (const char* word : {"1e309", "-1e400", "1e-400", "+1e999"}) {
    const std::string line = std::string("0 0 0 ") + word;
    EXPECT_EQ(problem_of(line, LineQuery::sphere), "'" + std::string(word) + "' is beyond the range of a double")
        << line;
  }
  EXPECT_EQ(problem_of("0 0 0", LineQuery::sphere), "expected 4 numbers (x y z r), found 3");
  EXPECT_EQ(problem_of("0 0 0 0 0", LineQuery::sphere), "expected 4 numbers (x y z r), found 5");
  EXPECT_EQ(problem_of(",,,", LineQuery::box), "expected 6 numbers (minx miny minz maxx maxy maxz), found 0");
}

TEST(QueryLines, HostileBytesAreQuotedPrintablyAndCut) {
  EXPECT_EQ(problem_of(std::string("1 2\0 3 4", 8), LineQuery::sphere), "'2\\x00' is not a finite number");
  EXPECT_EQ(problem_of("1 \x1b[31m 3 4", LineQuery::sphere), "'\\x1b[31m' is not a finite number");
  const std::string long_word(100000, 'a');
  EXPECT_EQ(problem_of("1 2 3 " + long_word, LineQuery::sphere),
            "'" + std::string(40, 'a') + "... (100000 characters)' is not a finite number");
}

TEST(QueryLines, AMillionNumbersAreCountedNotKept) {
  std::string line;
  for (int i = 0; i < 1'000'000; ++i) line += "1 ";
  EXPECT_EQ(problem_of(line, LineQuery::raycast), "expected 7 numbers (x y z dx dy dz max_range), found 1000000");
}

/// Every line the reader gives: number, values, problem.
std::vector<QueryLine> read_all(std::istream& in, LineQuery kind) {
  QueryLineReader reader(in, kind);
  std::vector<QueryLine> lines;
  while (const QueryLine* line = reader.next()) lines.push_back(*line);
  return lines;
}

TEST(QueryLines, LinesAreReadInOrderWithTheirNumbers) {
  std::istringstream in("# header\n1 2 3 4\n\n  \t\n1 2 3\n  # indented comment\n5 6 7 8\r\nx 1 2 3");
  const std::vector<QueryLine> lines = read_all(in, LineQuery::sphere);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].number, 2u);
  EXPECT_TRUE(lines[0].good());
  EXPECT_EQ(lines[0].values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(lines[1].number, 5u);
  EXPECT_EQ(lines[1].problem, "expected 4 numbers (x y z r), found 3");
  EXPECT_TRUE(lines[1].values.empty());
  EXPECT_EQ(lines[2].number, 7u);
  EXPECT_EQ(lines[2].values, (std::vector<double>{5, 6, 7, 8}));
  EXPECT_EQ(lines[3].number, 8u);
  EXPECT_EQ(lines[3].problem, "'x' is not a finite number");
}

TEST(QueryLines, TheReaderGivesEachLineBeforeTheNextArrives) {
  std::stringstream pipe;  // written and read in turns, as a pipe from a program that waits for answers
  QueryLineReader reader(pipe, LineQuery::sphere);
  pipe << "1 2 3 4\n";
  ASSERT_TRUE(reader.input_ready());
  const QueryLine* first = reader.next();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_FALSE(reader.input_ready());  // nothing more written yet: the command flushes its answers here
  pipe << "5 6 7 8\n";
  ASSERT_TRUE(reader.input_ready());
  const QueryLine* second = reader.next();
  ASSERT_NE(second, nullptr);
  EXPECT_EQ(second->number, 2u);
  EXPECT_EQ(second->values, (std::vector<double>{5, 6, 7, 8}));
  EXPECT_EQ(reader.next(), nullptr);
}

TEST(QueryLines, LinesOverTheLimitAreRefusedWithTheirLengthAndSkipped) {
  const std::string numbers = "1 2 3 4";
  const std::string padded_to_limit = numbers + std::string(kMaxQueryLineBytes - numbers.size(), ' ');
  const std::string long_line(3 * kMaxQueryLineBytes + 5, '7');
  const std::string long_comment = "# " + std::string(2 * kMaxQueryLineBytes, 'c');
  std::istringstream in(padded_to_limit + "\n" + padded_to_limit + " \n" + long_comment + "\n" + long_line + "\n" +
                        numbers + "\n" + long_line);
  const std::vector<QueryLine> lines = read_all(in, LineQuery::sphere);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0].number, 1u);  // exactly the limit: read whole
  EXPECT_EQ(lines[0].values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(lines[1].number, 2u);  // one byte more
  EXPECT_EQ(lines[1].problem, "the line holds " + std::to_string(kMaxQueryLineBytes + 1) + " bytes, more than the " +
                                  std::to_string(kMaxQueryLineBytes) + " a query line may hold");
  EXPECT_EQ(lines[2].number, 4u);  // the long comment (line 3) skipped
  EXPECT_EQ(lines[2].problem, "the line holds " + std::to_string(long_line.size()) + " bytes, more than the " +
                                  std::to_string(kMaxQueryLineBytes) + " a query line may hold");
  EXPECT_EQ(lines[3].number, 5u);
  EXPECT_EQ(lines[3].values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(lines[4].number, 6u);  // the last, with no newline
  EXPECT_EQ(lines[4].problem, lines[2].problem);
}

TEST(QueryLines, AStreamThatFailsIsAnError) {
  std::istringstream in("1 2 3 4\n");
  in.setstate(std::ios::badbit);
  QueryLineReader reader(in, LineQuery::sphere);
  EXPECT_THROW((void)reader.next(), std::runtime_error);
}

TEST(QueryLines, AnswersRefuseBadShapesWithTheLibrarysMessage) {
  MapConfig config;
  config.depth_levels = 4;  // +-0.8 m
  const OccupancyMap map(config);
  const std::vector<double> outside = {5, 0, 0, 0.1};
  const QueryAnswer far = answer_query_line(map, LineQuery::sphere, outside, {});
  EXPECT_FALSE(far.ok);
  EXPECT_NE(far.problem.find("outside the map"), std::string::npos) << far.problem;
  const std::vector<double> segment = {0, 0, 0, 0.5, 0, 0};
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (const double radius : {kNaN, std::numeric_limits<double>::infinity(), -0.5}) {
    LineQuerySettings settings;
    settings.radius = radius;
    const QueryAnswer capsule = answer_query_line(map, LineQuery::line, segment, settings);
    EXPECT_FALSE(capsule.ok) << radius;
    EXPECT_FALSE(capsule.problem.empty()) << radius;
  }
  const QueryAnswer unknown = answer_query_line(map, LineQuery::line, segment, {});
  EXPECT_TRUE(unknown.ok);
  EXPECT_TRUE(unknown.yes);  // an empty map is unknown, which blocks
  EXPECT_THROW((void)answer_query_line(map, LineQuery::box, outside, {}), std::logic_error);
}

}  // namespace
}  // namespace umbra::cli
