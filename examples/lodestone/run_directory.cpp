// The owner of a run's output directory; see run_directory.h.
#include "run_directory.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <regex>

#include "lodestone/cli/command_line.h"
#include "lodestone/core/base/error.h"
#include "lodestone/core/base/hash.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/output/stats_json.h"

namespace lodestone::examples {

namespace fs = std::filesystem;

namespace {

std::string gridText(const int dims[3], double dx) {
  char text[128];
  std::snprintf(text, sizeof text, "%d x %d x %d nodes at dx = %.6g m", dims[0], dims[1], dims[2], dx);
  return text;
}

std::uint64_t parseHash(const std::string& hex) {
  if (hex.size() != 16 || hex.find_first_not_of("0123456789abcdef") != std::string::npos)
    throw InvalidArgument(concat("'", hex, "' is not a content hash"));
  return std::stoull(hex, nullptr, 16);
}

}  // namespace

nlohmann::json RunIdentity::toJson() const {
  return {{"scene", scene},
          {"scene_file", sceneFile},
          {"scene_hash", hashHex(sceneHash)},
          {"grid", {{"dims", {dims[0], dims[1], dims[2]}}, {"dx_m", dx}}}};
}

RunIdentity RunIdentity::fromJson(const nlohmann::json& j) {
  try {
    RunIdentity id;
    id.scene = j.at("scene").get<std::string>();
    id.sceneFile = j.at("scene_file").get<std::string>();
    id.sceneHash = parseHash(j.at("scene_hash").get<std::string>());
    const nlohmann::json& dims = j.at("grid").at("dims");
    for (int a = 0; a < 3; ++a) id.dims[a] = dims.at(std::size_t(a)).get<int>();
    id.dx = j.at("grid").at("dx_m").get<double>();
    return id;
  } catch (const nlohmann::json::exception& e) {
    throw InvalidArgument(concat("not a run identity (", e.what(), ")"));
  }
}

std::string RunIdentity::differenceFrom(const RunIdentity& o) const {
  if (scene != o.scene) return concat("it is scene '", scene, "', not '", o.scene, "'");
  if (sceneHash != o.sceneHash)
    return concat("scene '", scene, "' has changed (content hash ", hashHex(sceneHash), ", now ",
                  hashHex(o.sceneHash), ")");
  if (!std::equal(dims, dims + 3, o.dims) || dx != o.dx)
    return concat("its grid is ", gridText(dims, dx), ", not ", gridText(o.dims, o.dx), " (--dx or --full differ)");
  return "";
}

std::string RunIdentity::describe() const {
  return concat("scene '", scene, "' (", sceneFile, ", content hash ", hashHex(sceneHash), "), grid ",
                gridText(dims, dx));
}

RunIdentity runIdentity(const plugin::Scene& scene) {
  RunIdentity id;
  id.scene = scene.name;
  id.sceneFile = scene.file;
  id.sceneHash = scene.contentHash;
  const GridSpec& g = scene.settings.grid;
  id.dims[0] = g.dims.i;
  id.dims[1] = g.dims.j;
  id.dims[2] = g.dims.k;
  id.dx = g.dx;
  return id;
}

std::string checkpointTag(const CheckpointOrigin& origin) {
  nlohmann::json j = origin.identity.toJson();
  j["frames"] = {origin.first, origin.last};
  return j.dump();
}

CheckpointOrigin checkpointOrigin(const std::string& tag) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(tag);
  } catch (const nlohmann::json::exception&) {
    throw InvalidArgument("it was written by an older lodestone (no scene content hash): start the run again");
  }
  CheckpointOrigin o;
  o.identity = RunIdentity::fromJson(j);
  try {
    o.first = j.at("frames").at(0).get<int>();
    o.last = j.at("frames").at(1).get<int>();
  } catch (const nlohmann::json::exception& e) {
    throw InvalidArgument(concat("its tag has no frame range (", e.what(), ")"));
  }
  return o;
}

std::string frameNumber(int frame) {
  char digits[32];
  std::snprintf(digits, sizeof digits, "%04d", frame);
  return digits;
}

std::vector<int> frameFiles(const std::string& dir, const std::string& prefix, const std::string& ext) {
  std::vector<int> frames;
  if (!std::filesystem::is_directory(dir)) return frames;
  const std::regex pattern(prefix + "([0-9]{4,})\\." + ext);
  for (const std::filesystem::directory_entry& e : std::filesystem::directory_iterator(dir)) {
    std::smatch m;
    const std::string name = e.path().filename().string();
    if (std::regex_match(name, m, pattern)) frames.push_back(std::stoi(m[1].str()));
  }
  std::sort(frames.begin(), frames.end());
  return frames;
}

std::string checkpointName(int frame) { return "checkpoint_" + frameNumber(frame) + ".lsck"; }

std::vector<int> checkpointFrames(const std::string& dir) {
  std::vector<int> frames;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    int frame = -1;
    char tail[8] = {};
    if (std::sscanf(name.c_str(), "checkpoint_%d.%7s", &frame, tail) == 2 && std::string(tail) == "lsck" &&
        frame >= 0 && name == checkpointName(frame))
      frames.push_back(frame);
  }
  if (ec) throw Error(concat("cannot list '", dir, "' (", ec.message(), ")"));
  std::sort(frames.rbegin(), frames.rend());
  return frames;
}

std::string readFrameRange(const std::string& text, int& first, int& last, int lowest) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) return concat("expected A:B, got '", text, "'");
  for (const std::string& part : {text.substr(0, colon), text.substr(colon + 1)}) {
    const std::optional<double> v = cli::toNumber(part);
    if (!v) return concat("'", part, "' is not a number");
    if (*v != std::floor(*v) || std::fabs(*v) > 1e9) return concat("'", part, "' is not a whole number of frames");
  }
  first = int(*cli::toNumber(text.substr(0, colon)));
  last = int(*cli::toNumber(text.substr(colon + 1)));
  if (first < lowest || last < first) return concat("need ", lowest, " <= A <= B, got ", text);
  return "";
}

std::string commandLine(const std::vector<std::string>& args) {
  std::string line;
  for (const std::string& a : args) {
    if (!line.empty()) line += ' ';
    const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                         "0123456789_-+=.,:/@%") == std::string::npos;
    if (plain) {
      line += a;
      continue;
    }
    line += '\'';
    for (char c : a) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

bool isRunOutput(const std::string& name) {
  static const std::regex pattern(
      R"(((frame_[0-9]{4,}\.(ply|png))|((fields|particles|surface|volume)_[0-9]{4,}\.vdb)|((mesh|field_lines)_[0-9]{4,}\.(ply|obj))|)"
      R"((checkpoint_[0-9]{4,}\.lsck)|stats\.json|contact_sheet\.png|lodestone_run\.json))");
  if (std::regex_match(name, pattern)) return true;
  // The hidden temporaries of atomic writes (".frame_0001.ply.tmp-XXXXXX").
  const std::size_t tmp = name.rfind(".tmp-");
  return name.size() > 1 && name[0] == '.' && tmp != std::string::npos && isRunOutput(name.substr(1, tmp - 1));
}

RunDirectory::RunDirectory(const std::string& dir, const RunIdentity& identity, bool clean)
    : dir_(dir), identity_(identity) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw Error(concat("cannot create the output directory '", dir, "'", ec ? " (" + ec.message() + ")" : ""));
  const std::string lock = (fs::path(dir) / kLock).string();
  lockFd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lockFd_ < 0) throw Error(concat("cannot create '", lock, "' (", std::strerror(errno), ")"));
  if (::flock(lockFd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char pid[32] = {};
    const ssize_t n = ::pread(lockFd_, pid, sizeof pid - 1, 0);
    ::close(lockFd_);
    lockFd_ = -1;
    if (err == EWOULDBLOCK)
      throw Error(concat("'", dir, "' is in use: another lodestone run", n > 0 ? concat(" (pid ", pid, ")") : "",
                         " is writing to it; wait for it to end or choose another --out"));
    throw Error(concat("cannot lock '", lock, "' (", std::strerror(err), ")"));
  }
  const std::string pid = std::to_string(::getpid());
  if (::ftruncate(lockFd_, 0) != 0 || ::pwrite(lockFd_, pid.data(), pid.size(), 0) != ssize_t(pid.size()))
    throw Error(concat("cannot write '", lock, "' (", std::strerror(errno), ")"));

  // Who wrote the directory before.
  std::string refusal;
  const fs::path manifest = fs::path(dir) / kManifest;
  if (fs::exists(manifest)) {
    try {
      previous_ = plugin::parseJsonFile(manifest.string());
      const RunIdentity before = RunIdentity::fromJson(previous_.at("identity"));
      const std::string difference = before.differenceFrom(identity);
      if (!difference.empty())
        refusal = concat("it holds the output of another run (", kManifest, "): ", difference);
    } catch (const std::exception& e) {
      refusal = concat("its ", kManifest, " cannot be read (", e.what(), ")");
    }
  } else {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (isRunOutput(e.path().filename().string())) found.push_back(e.path().filename().string());
    if (!found.empty()) {
      std::sort(found.begin(), found.end());
      refusal = concat("it holds lodestone output (", found.front(), found.size() > 1 ? concat(" and ", found.size() - 1, " more") : "",
                       ") but no ", kManifest, " saying which run wrote it");
    }
  }
  if (refusal.empty()) return;
  if (!clean)
    throw Error(concat("'", dir, "': ", refusal, "; run with --clean to delete that output and start over, or "
                                                 "choose another --out"));
  std::size_t removed = 0;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (isRunOutput(e.path().filename().string()) && e.is_regular_file()) {
      fs::remove(e.path(), ec);
      if (ec) throw Error(concat("--clean: cannot delete '", e.path().string(), "' (", ec.message(), ")"));
      ++removed;
    }
  previous_ = nlohmann::json();
  std::printf("--clean: deleted %zu files of the earlier run in %s\n", removed, dir.c_str());
}

RunDirectory::~RunDirectory() {
  if (lockFd_ >= 0) ::close(lockFd_);  // releases the lock
}

void RunDirectory::record(const std::string& command, int first, int last, const std::string& status,
                          int complete) const {
  nlohmann::json m;
  m["identity"] = identity_.toJson();
  m["command"] = command;
  m["lodestone_version"] = LODESTONE_VERSION_STRING;
  m["frames"] = {first, last};
  m["status"] = status;
  m["last_complete_frame"] = complete;
  output::writeJsonFile((fs::path(dir_) / kManifest).string(), m);
}

void RunDirectory::pruneCheckpoints(int frame, int keep) const {
  if (keep <= 0) return;
  int kept = 1;  // `frame`'s own
  for (const int f : checkpointFrames(dir_)) {
    if (f >= frame) continue;
    if (kept < keep) {
      ++kept;
      continue;
    }
    std::error_code ec;
    fs::remove(fs::path(dir_) / checkpointName(f), ec);
    if (ec) throw Error(concat("--keep-checkpoints: cannot delete '", checkpointName(f), "' (", ec.message(), ")"));
  }
}

}  // namespace lodestone::examples
