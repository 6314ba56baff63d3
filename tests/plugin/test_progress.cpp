// Progress lines: the pure formatters (durations, stage split, the line
// itself with its ETA) and the printer's two modes, plain lines (throttled)
// and in-place terminal updates with '\r' and padding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "lodestone/core/base/error.h"
#include "lodestone/plugin/output/progress.h"

using namespace lodestone;
using namespace lodestone::output;

TEST(Progress, FormatDuration) {
  EXPECT_EQ(formatDuration(0.0), "0.00 s");
  EXPECT_EQ(formatDuration(0.4249), "0.42 s");
  EXPECT_EQ(formatDuration(9.994), "9.99 s");
  EXPECT_EQ(formatDuration(12.34), "12.3 s");
  EXPECT_EQ(formatDuration(62.0), "1m02s");
  EXPECT_EQ(formatDuration(245.4), "4m05s");
  EXPECT_EQ(formatDuration(3723.0), "1h02m03s");
  EXPECT_EQ(formatDuration(-1.0), "--");
  EXPECT_EQ(formatDuration(std::nan("")), "--");
}

TEST(Progress, FormatStageSplit) {
  EXPECT_EQ(formatStageSplit({{"p2g", 1.0}, {"solve", 2.0}, {"g2p", 1.0}}), "p2g 25%, solve 50%, g2p 25%");
  EXPECT_EQ(formatStageSplit({{"a", 1.0}, {"b", 0.0}}), "a 100%, b 0%");
  EXPECT_EQ(formatStageSplit({}), "");
  StageTimes t;
  t.add("transfer", 0.3);
  t.add("solve", 0.6);
  t.add("transfer", 0.1);
  EXPECT_DOUBLE_EQ(t.total(), 1.0);
  EXPECT_DOUBLE_EQ(t.seconds("transfer"), 0.4);
  EXPECT_EQ(t.seconds("none"), 0.0);
  EXPECT_EQ(t.split(), "transfer 40%, solve 60%");
}

TEST(Progress, FormatProgressLine) {
  // 62 s for 12 frames: 228 frames left take 62 / 12 * 228 = 1178 s.
  EXPECT_EQ(formatProgressLine(12, 240, 62.0, "p2g 31%, solve 52%, g2p 17%"),
            "frame 12/240    5.0%  elapsed 1m02s  ETA 19m38s  | p2g 31%, solve 52%, g2p 17%");
  EXPECT_EQ(formatProgressLine(0, 10, 0.5), "frame 0/10    0.0%  elapsed 0.50 s  ETA --");
  EXPECT_EQ(formatProgressLine(10, 10, 3.0), "frame 10/10  100.0%  elapsed 3.00 s  ETA 0.00 s");
  EXPECT_THROW(formatProgressLine(11, 10, 1.0), InvalidArgument);
  EXPECT_THROW(formatProgressLine(-1, 10, 1.0), InvalidArgument);
  EXPECT_THROW(formatProgressLine(0, 0, 1.0), InvalidArgument);
}

TEST(Progress, FormatProgressLineShowsSceneFrameNumbers) {
  // Frames 1001..1100 of a scene whose initial frame is 1000: 25 of 100 done.
  EXPECT_EQ(formatProgressLine(25, 100, 10.0, "", 1000), "frame 1025/1100   25.0%  elapsed 10.0 s  ETA 30.0 s");
}

TEST(Progress, PlainLinesAreThrottled) {
  std::ostringstream out;
  ProgressOptions o;
  o.terminal = false;
  o.plainInterval = 10.0;
  {
    ProgressPrinter p(out, 4, o);
    p.update(1, 0.5);   // first: printed
    p.update(2, 5.0);   // 4.5 s later: skipped
    p.update(3, 11.0);  // 10.5 s later: printed
    p.message("warning: CFL 0.9");
    p.update(4, 12.0);  // last frame: always printed
  }
  EXPECT_EQ(out.str(),
            "frame 1/4   25.0%  elapsed 0.50 s  ETA 1.50 s\n"
            "frame 3/4   75.0%  elapsed 11.0 s  ETA 3.67 s\n"
            "warning: CFL 0.9\n"
            "frame 4/4  100.0%  elapsed 12.0 s  ETA 0.00 s\n");
  EXPECT_EQ(out.str().find('\r'), std::string::npos);
}

TEST(Progress, TerminalRedrawsInPlace) {
  std::ostringstream out;
  ProgressOptions o;
  o.terminal = true;
  o.terminalInterval = 0.0;
  ProgressPrinter p(out, 100, o);
  p.update(1, 1.0, "solve 100%");
  const std::string first = "frame 1/100    1.0%  elapsed 1.00 s  ETA 1m39s  | solve 100%";
  EXPECT_EQ(out.str(), "\r" + first);
  p.update(2, 2.0);  // shorter: padded with spaces over the old text
  const std::string second = "frame 2/100    2.0%  elapsed 2.00 s  ETA 1m38s";
  EXPECT_EQ(out.str(), "\r" + first + "\r" + second + std::string(first.size() - second.size(), ' '));
  EXPECT_EQ(out.str().find('\n'), std::string::npos);

  out.str("");
  p.message("note");  // cleared line, message, bar redrawn
  EXPECT_EQ(out.str(), "\r" + std::string(second.size(), ' ') + "\rnote\n" + second);

  out.str("");
  p.finish();
  EXPECT_EQ(out.str(), "\n");
  p.finish();  // idempotent
  EXPECT_EQ(out.str(), "\n");
}

TEST(Progress, RejectsBadArguments) {
  std::ostringstream out;
  EXPECT_THROW(ProgressPrinter(out, 0), InvalidArgument);
  ProgressOptions o;
  o.plainInterval = -1;
  EXPECT_THROW(ProgressPrinter(out, 5, o), InvalidArgument);
  ProgressPrinter p(out, 5);
  EXPECT_THROW(p.update(6, 1.0), InvalidArgument);
}
