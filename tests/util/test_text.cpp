#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <ctime>

#include "crowdslam/util/error.h"
#include "crowdslam/util/text.h"
#include "test_support.h"

using namespace crowdslam;

TEST(Text, SplitFieldsDropsEmptyAndHandlesCommasTabs) {
  const auto f = split_fields(" 1.5,\t2  ,3\r");
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[0], "1.5");
  EXPECT_EQ(f[2], "3");
  EXPECT_EQ(split_fields("a,b", false).size(), 1u);
}

TEST(Text, ParseDoubleIsStrict) {
  EXPECT_DOUBLE_EQ(*parse_double("1548339819.87426"), 1548339819.87426);
  EXPECT_FALSE(parse_double("1.5abc").has_value());
  EXPECT_FALSE(parse_double("").has_value());
  EXPECT_TRUE(std::isnan(*parse_double("nan")));
  EXPECT_EQ(*parse_int(" 42 "), 42);
  EXPECT_FALSE(parse_int("4.2").has_value());
}

TEST(Text, ReadLinesMissingFileNamesTheFile) {
  try {
    read_lines("/nonexistent/list.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/list.txt"), std::string::npos);
  }
}

TEST(Text, ReadLinesStripsCarriageReturns) {
  test::TempDir tmp;
  test::write_text(tmp / "a.txt", "x\r\ny\n");
  const auto lines = read_lines((tmp / "a.txt").string());
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "x");
}

TEST(Text, UtcNowIsTheCurrentTimeInTheGivenFormat) {
  const std::time_t before = std::time(nullptr);
  const std::string iso = utc_now();
  const std::time_t after = std::time(nullptr);
  ASSERT_EQ(iso.size(), 20u) << iso;  // 2026-12-02T16:20:00Z
  std::tm tm{};
  ASSERT_NE(strptime(iso.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm), nullptr) << iso;
  const std::time_t parsed = timegm(&tm);
  EXPECT_GE(parsed, before);
  EXPECT_LE(parsed, after);
  const std::string report = utc_now("%Y-%m-%d %H:%M UTC");
  EXPECT_EQ(report.substr(0, 10), iso.substr(0, 10));
  EXPECT_EQ(report.substr(report.size() - 4), " UTC");
}

// Issue 37, finding 6: /dev/zero read for ever (16.8 GB); a directory said "read error".
TEST(Text, ReadLinesRefusesSpecialFilesDirectoriesAndEndlessLines) {
  test::TempDir tmp;
  const auto message = [](const std::string& path) {
    try {
      read_lines(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message("/dev/zero"), "/dev/zero: not a regular file (a device, FIFO or socket is not read)");
  EXPECT_EQ(message(tmp.path().string()), tmp.path().string() + ": is a directory, not a file");
  const auto fifo = tmp / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(message(fifo.string()).find("not a regular file"), std::string::npos);  // and no hang
  test::write_text(tmp / "long.txt", "ok\n" + std::string(3000, 'x') + "\nok\n");
  EXPECT_EQ(read_lines((tmp / "long.txt").string(), 4096).size(), 3u);
  try {
    read_lines((tmp / "long.txt").string(), 1000);
    FAIL() << "a line over the limit must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("long.txt:2: line longer than 1000 bytes"), std::string::npos) << e.what();
  }
  test::write_text(tmp / "last.txt", "a\nb");  // no final newline
  EXPECT_EQ(read_lines((tmp / "last.txt").string()), (std::vector<std::string>{"a", "b"}));
}
