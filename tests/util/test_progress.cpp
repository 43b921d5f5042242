// ProgressLine (issue 13, progress): the line's text, and plain lines when the output is not a terminal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "crowdslam/util/progress.h"

using crowdslam::ProgressLine;

TEST(ProgressLine, FormatsDoneTotalRateEtaAndDetail) {
  EXPECT_EQ(ProgressLine::format(120, 927, "frame", 40.0, "ok"), "frame 120/927 (13 %)  40.0 frames/s  ETA 21 s  ok");
  EXPECT_EQ(ProgressLine::format(927, 927, "frame", 40.0, ""), "frame 927/927 (100 %)  40.0 frames/s");
  EXPECT_EQ(ProgressLine::format(5, 0, "frame", 0.0, "lost"), "frame 5  lost");  // unknown total (camera)
}

namespace {
// Runs `fill` on a ProgressLine writing to a temporary file (not a terminal) and returns the text.
template <typename Fill>
std::string plain_output(Fill fill) {
  std::FILE* file = std::tmpfile();
  EXPECT_NE(file, nullptr);
  if (!file) return {};
  fill(file);
  std::rewind(file);
  std::string text;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, file)) text += buffer;
  std::fclose(file);
  return text;
}

size_t count_lines(const std::string& text) { return static_cast<size_t>(std::count(text.begin(), text.end(), '\n')); }
}  // namespace

TEST(ProgressLine, NotATerminalGivesAPlainLineEveryNItemsAndALastOneAtTheEnd) {
  const std::string text = plain_output([](std::FILE* file) {
    ProgressLine line(true, 10, "frame", 4, file);
    EXPECT_FALSE(line.on_terminal());
    for (size_t i = 1; i <= 10; ++i) line.update(i, "ok");
  });
  EXPECT_EQ(text.find('\r'), std::string::npos);  // never redrawn in place
  EXPECT_NE(text.find("frame 4/10 (40 %)"), std::string::npos) << text;
  EXPECT_NE(text.find("frame 8/10 (80 %)"), std::string::npos) << text;
  EXPECT_NE(text.find("frame 10/10 (100 %)"), std::string::npos) << text;  // by finish()
  EXPECT_EQ(count_lines(text), 3u) << text;
}

TEST(ProgressLine, PlainLinesEveryTenthOfTheTotalByDefaultAtMostEvery100) {
  const std::string small = plain_output([](std::FILE* file) {
    ProgressLine line(true, 30, "image", 0, file);
    for (size_t i = 1; i <= 30; ++i) line.update(i, "");
  });
  EXPECT_EQ(count_lines(small), 10u) << small;  // every 3
  EXPECT_NE(small.find("image 3/30 (10 %)"), std::string::npos) << small;
  const std::string large = plain_output([](std::FILE* file) {
    ProgressLine line(true, 5000, "frame", 0, file);
    for (size_t i = 1; i <= 450; ++i) line.update(i, "");
  });
  EXPECT_EQ(count_lines(large), 5u) << large;  // 100, 200, 300, 400 and the last (450) at the end
  EXPECT_NE(large.find("frame 450/5000"), std::string::npos) << large;
  EXPECT_NE(large.find("ETA"), std::string::npos) << large;
}

TEST(ProgressLine, DueSaysWhenAPlainLineIsPrinted) {
  plain_output([](std::FILE* file) {
    ProgressLine line(true, 10, "frame", 5, file);
    EXPECT_FALSE(line.due(4));
    EXPECT_TRUE(line.due(5));
    line.update(5, "");
    EXPECT_FALSE(line.due(5));  // already shown
    line.finish();
    EXPECT_FALSE(line.due(10));  // finished: nothing more
  });
}

TEST(ProgressLine, DisabledPrintsNothing) {
  const std::string text = plain_output([](std::FILE* file) {
    ProgressLine quiet(false, 10, "frame", 1, file);
    for (size_t i = 1; i <= 10; ++i) quiet.update(i, "ok");
    EXPECT_FALSE(quiet.due(5));
    quiet.finish();
  });
  EXPECT_EQ(text, "");
}
