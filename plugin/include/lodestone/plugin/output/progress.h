#pragma once
// Progress reporting for long runs of the `lodestone` program:
//   frame 12/240   5.0%  elapsed 1m02s  ETA 19m45s  | p2g 31%, solve 52%, g2p 17%
// On a terminal the line is redrawn in place ("\r", padded with spaces over
// the previous text); otherwise (a log file, a pipe) each update is a plain
// line, throttled so that long runs do not flood the log. Whether the stream
// is a terminal is the caller's flag (see isTerminal), so both modes are
// testable with a std::ostringstream. The formatting functions are pure.
#include <chrono>
#include <cstdio>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace lodestone::output {

/// Compact durations: "0.42 s", "12.3 s", "4m05s", "1h02m03s"; "--" when
/// negative or not finite.
std::string formatDuration(double seconds);

/// Per-stage shares of the total time, in the order given:
/// "p2g 31%, solve 52%, g2p 17%" (rounded; "" when empty or all zero).
std::string formatStageSplit(const std::vector<std::pair<std::string, double>>& stageSeconds);

/// "frame k/N  pp.p%  elapsed E  ETA T" (+ "  | split" when `split` is not
/// empty), k and N shown as firstFrame + frame and firstFrame + total (a
/// scene's frame numbers: firstFrame its initial frame). The ETA assumes the
/// remaining frames take the mean time so far ("--" before the first
/// frame). Throws lodestone::InvalidArgument unless 0 <= frame <= total and
/// total >= 1.
std::string formatProgressLine(int frame, int total, double elapsedSeconds, const std::string& split = "",
                               int firstFrame = 0);

/// Whether the C stream is a terminal (isatty).
bool isTerminal(std::FILE* stream);

/// Accumulates seconds per named stage, in first-seen order.
class StageTimes {
 public:
  void add(const std::string& stage, double seconds);
  double total() const;
  double seconds(const std::string& stage) const;  ///< 0 for an unknown stage
  const std::vector<std::pair<std::string, double>>& stages() const { return stages_; }
  std::string split() const { return formatStageSplit(stages_); }

 private:
  std::vector<std::pair<std::string, double>> stages_;
};

struct ProgressOptions {
  bool terminal = false;  ///< redraw one line with '\r' (else print plain lines)
  /// Shortest time (s) between two printed updates; the first and the last
  /// frame are always printed. Defaults suit a terminal and a log file.
  double terminalInterval = 0.1;
  double plainInterval = 10.0;
  /// Added to the frame numbers shown (formatProgressLine's firstFrame).
  int firstFrame = 0;
};

class ProgressPrinter {
 public:
  /// Reports `total` (>= 1) frames to `out`, which must outlive the printer.
  ProgressPrinter(std::ostream& out, int total, ProgressOptions options = {});

  /// Frame `frame` (0..total) is done; elapsed time from the internal clock
  /// (started at construction).
  void update(int frame, const std::string& split = "");
  /// Same with the elapsed time (s) given, for tests and replay.
  void update(int frame, double elapsedSeconds, const std::string& split = "");
  /// Prints a separate message line (warnings...) without garbling the bar.
  void message(const std::string& text);
  /// Ends the progress line (a newline on a terminal; idempotent).
  void finish();
  ~ProgressPrinter();

  ProgressPrinter(const ProgressPrinter&) = delete;
  ProgressPrinter& operator=(const ProgressPrinter&) = delete;

 private:
  void draw(const std::string& line);
  void clearLine();

  std::ostream& out_;
  int total_;
  ProgressOptions options_;
  std::chrono::steady_clock::time_point start_;
  double lastPrinted_ = -1;  // elapsed s at the last printed update; < 0: none yet
  std::string lastLine_;     // terminal mode: the line currently shown
  bool open_ = false;        // terminal mode: a bar is on the current line
};

}  // namespace lodestone::output
