// ProgressLine (issue 13, progress): the line's text, and plain lines when the output is not a terminal.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "crowdslam/util/progress.h"

using crowdslam::ProgressLine;

TEST(ProgressLine, FormatsDoneTotalRateEtaAndDetail) {
  EXPECT_EQ(ProgressLine::format(120, 927, "frame", 40.0, "ok"), "frame 120/927 (13 %)  40.0 frames/s  ETA 21 s  ok");
  EXPECT_EQ(ProgressLine::format(927, 927, "frame", 40.0, ""), "frame 927/927 (100 %)  40.0 frames/s");
  EXPECT_EQ(ProgressLine::format(5, 0, "frame", 0.0, "lost"), "frame 5  lost");  // unknown total (camera)
}

TEST(ProgressLine, NotATerminalGivesAPlainLineEveryNItemsAndQuietGivesNothing) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressLine line(true, 10, "frame", 4, file);
    EXPECT_FALSE(line.on_terminal());
    for (size_t i = 1; i <= 10; ++i) line.update(i, "ok");
  }
  {
    ProgressLine quiet(false, 10, "frame", 1, file);
    for (size_t i = 1; i <= 10; ++i) quiet.update(i, "ok");
  }
  std::rewind(file);
  std::string text;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, file)) text += buffer;
  std::fclose(file);
  EXPECT_EQ(text.find('\r'), std::string::npos);  // never redrawn in place
  EXPECT_NE(text.find("frame 4/10 (40 %)"), std::string::npos) << text;
  EXPECT_NE(text.find("frame 8/10 (80 %)"), std::string::npos) << text;
  size_t lines = 0;
  for (char c : text) lines += c == '\n' ? 1 : 0;
  EXPECT_EQ(lines, 2u) << text;
}
