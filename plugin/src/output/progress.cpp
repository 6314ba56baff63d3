#include "lodestone/plugin/output/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "lodestone/core/base/error.h"

namespace lodestone::output {

std::string formatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--";
  char buf[48];
  if (seconds < 9.995) {
    std::snprintf(buf, sizeof buf, "%.2f s", seconds);
  } else if (seconds < 59.95) {
    std::snprintf(buf, sizeof buf, "%.1f s", seconds);
  } else {
    const long long total = std::llround(seconds);
    const long long h = total / 3600, m = (total / 60) % 60, s = total % 60;
    if (h > 0)
      std::snprintf(buf, sizeof buf, "%lldh%02lldm%02llds", h, m, s);
    else
      std::snprintf(buf, sizeof buf, "%lldm%02llds", m, s);
  }
  return buf;
}

std::string formatStageSplit(const std::vector<std::pair<std::string, double>>& stageSeconds) {
  double total = 0;
  for (const auto& s : stageSeconds)
    if (std::isfinite(s.second) && s.second > 0) total += s.second;
  if (!(total > 0)) return "";
  std::string r;
  for (const auto& s : stageSeconds) {
    const double share = std::isfinite(s.second) && s.second > 0 ? s.second / total : 0.0;
    if (!r.empty()) r += ", ";
    r += s.first + " " + std::to_string(std::lround(100.0 * share)) + "%";
  }
  return r;
}

std::string formatProgressLine(int frame, int total, double elapsedSeconds, const std::string& split,
                               int firstFrame) {
  require(total >= 1, "progress: the number of frames must be >= 1, got ", total);
  require(frame >= 0 && frame <= total, "progress: frame must be in [0, ", total, "], got ", frame);
  const double eta = frame > 0 ? elapsedSeconds / frame * (total - frame) : -1.0;
  char percent[16];
  std::snprintf(percent, sizeof percent, "%5.1f%%", 100.0 * frame / total);
  std::string line = concat("frame ", firstFrame + frame, "/", firstFrame + total, "  ", percent, "  elapsed ", formatDuration(elapsedSeconds),
                            "  ETA ", formatDuration(eta));
  if (!split.empty()) line += "  | " + split;
  return line;
}

bool isTerminal(std::FILE* stream) { return stream != nullptr && ::isatty(::fileno(stream)) == 1; }

void StageTimes::add(const std::string& stage, double secs) {
  for (auto& s : stages_)
    if (s.first == stage) {
      s.second += secs;
      return;
    }
  stages_.emplace_back(stage, secs);
}

double StageTimes::total() const {
  double t = 0;
  for (const auto& s : stages_) t += s.second;
  return t;
}

double StageTimes::seconds(const std::string& stage) const {
  for (const auto& s : stages_)
    if (s.first == stage) return s.second;
  return 0.0;
}

ProgressPrinter::ProgressPrinter(std::ostream& out, int total, ProgressOptions options)
    : out_(out), total_(total), options_(options), start_(std::chrono::steady_clock::now()) {
  require(total >= 1, "progress: the number of frames must be >= 1, got ", total);
  require(options.terminalInterval >= 0 && options.plainInterval >= 0,
          "progress: update intervals must be >= 0 s, got ", options.terminalInterval, " and ", options.plainInterval);
}

ProgressPrinter::~ProgressPrinter() {
  try {
    finish();
  } catch (...) {  // never throw from a destructor
  }
}

void ProgressPrinter::update(int frame, const std::string& split) {
  update(frame, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(), split);
}

void ProgressPrinter::update(int frame, double elapsedSeconds, const std::string& split) {
  const std::string line = formatProgressLine(frame, total_, elapsedSeconds, split, options_.firstFrame);
  const double interval = options_.terminal ? options_.terminalInterval : options_.plainInterval;
  const bool due = lastPrinted_ < 0 || frame == total_ || elapsedSeconds - lastPrinted_ >= interval;
  if (!due) return;
  lastPrinted_ = elapsedSeconds;
  draw(line);
}

void ProgressPrinter::draw(const std::string& line) {
  if (!options_.terminal) {
    out_ << line << '\n' << std::flush;
    return;
  }
  out_ << '\r' << line;
  if (lastLine_.size() > line.size()) out_ << std::string(lastLine_.size() - line.size(), ' ');
  out_ << std::flush;
  lastLine_ = line;
  open_ = true;
}

void ProgressPrinter::clearLine() {
  if (!open_) return;
  out_ << '\r' << std::string(lastLine_.size(), ' ') << '\r';
}

void ProgressPrinter::message(const std::string& text) {
  if (!options_.terminal) {
    out_ << text << '\n' << std::flush;
    return;
  }
  clearLine();
  out_ << text << '\n';
  if (open_) out_ << lastLine_;  // redraw the bar below the message
  out_ << std::flush;
}

void ProgressPrinter::finish() {
  if (options_.terminal && open_) out_ << '\n' << std::flush;
  open_ = false;
  lastLine_.clear();
}

}  // namespace lodestone::output
