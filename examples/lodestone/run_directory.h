#pragma once
// The owner of a `lodestone run` output directory. While a run writes to DIR
// it holds an exclusive lock on DIR/lodestone_run.lock (flock: released when
// the process ends, however it ends), so a second run into DIR is refused
// instead of interleaving its frames. DIR/lodestone_run.json (the manifest)
// records what wrote the directory: the run's identity (scene name, file,
// content hash, grid), the command line, the lodestone version, the frame
// range, its status (running, complete, interrupted, failed) and the last
// complete frame. A run whose identity differs from the manifest's, or a
// directory with lodestone output but no manifest, is refused unless the run
// asks to start clean (--clean), which deletes the files a run writes there
// (and nothing else) first.
//
// Checkpoints carry the same identity and the frame range of the run that
// wrote them in their tag (checkpointTag / checkpointOrigin), so --resume
// can refuse a checkpoint of a changed scene or of another frame range.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodestone/plugin/scene.h"

namespace lodestone::examples {

/// What makes two runs compute the same frames: the scene's text (content
/// hash) and the grid its options chose (--dx, --full).
struct RunIdentity {
  std::string scene;      ///< the scene's name
  std::string sceneFile;  ///< as given on the command line (not compared)
  std::uint64_t sceneHash = 0;
  int dims[3] = {0, 0, 0};  ///< MPM grid nodes per axis
  double dx = 0;            ///< m

  nlohmann::json toJson() const;
  /// Throws lodestone::InvalidArgument when `j` is not an identity.
  static RunIdentity fromJson(const nlohmann::json& j);
  /// "" when `other` computes the same frames, otherwise what differs
  /// ("the scene file's content changed (hash A, now B)").
  std::string differenceFrom(const RunIdentity& other) const;
  /// "scene 'spike' (spike.json, content hash H), grid 35 x 35 x 35 nodes at dx = 0.0117 m".
  std::string describe() const;
};

RunIdentity runIdentity(const plugin::Scene& scene);

/// Where a checkpoint came from: the run's identity and frame range.
struct CheckpointOrigin {
  RunIdentity identity;
  int first = 1, last = 1;  ///< the frames the run wrote (--frames A:B)
};

/// The tag stored in a checkpoint (JSON text).
std::string checkpointTag(const CheckpointOrigin& origin);
/// The origin a tag records. Throws lodestone::InvalidArgument for a tag
/// this lodestone did not write (an older version's or another program's).
CheckpointOrigin checkpointOrigin(const std::string& tag);

/// A frame number (>= 0) as file names carry it: at least four digits
/// ("0042", "12345").
std::string frameNumber(int frame);
/// checkpoint_NNNN.lsck (NNNN: frameNumber)
std::string checkpointName(int frame);

/// The frame numbers of the files PREFIXNNNN.EXT (four or more digits) in
/// `dir`, ascending; none when `dir` is not a directory.
std::vector<int> frameFiles(const std::string& dir, const std::string& prefix, const std::string& ext);
/// The frames of the checkpoint_NNNN.lsck files in `dir`, newest first.
std::vector<int> checkpointFrames(const std::string& dir);

/// "A:B", lowest <= A <= B (whole numbers), into first and last; returns
/// the error ("" when good): the rule of --frames.
std::string readFrameRange(const std::string& text, int& first, int& last, int lowest = 1);

/// The command line as one shell-quoted string.
std::string commandLine(const std::vector<std::string>& args);

class RunDirectory {
 public:
  /// Creates `dir`, takes its lock (throws lodestone::Error when another run
  /// holds it, naming its pid) and checks the manifest: a directory with
  /// another run's output is refused (lodestone::Error saying what differs)
  /// unless `clean`, which deletes that output first.
  RunDirectory(const std::string& dir, const RunIdentity& identity, bool clean);
  ~RunDirectory();
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;

  /// Rewrites the manifest (atomically): identity, `command`, version,
  /// frames first..last, `status` and the last complete frame.
  void record(const std::string& command, int first, int last, const std::string& status, int complete) const;

  /// The manifest found when the run started (null when there was none or
  /// it was cleaned).
  const nlohmann::json& previous() const { return previous_; }

  /// Deletes checkpoint files of frames before `frame` beyond the newest
  /// `keep` - 1 of them (with `frame`'s own, `keep` remain); keep = 0: none.
  void pruneCheckpoints(int frame, int keep) const;

  static constexpr const char* kManifest = "lodestone_run.json";
  static constexpr const char* kLock = "lodestone_run.lock";

 private:
  std::string dir_;
  RunIdentity identity_;
  nlohmann::json previous_;
  int lockFd_ = -1;
};

/// True for the names of the files `lodestone run` writes in its output
/// directory (frame_NNNN.ply/.png, fields_NNNN.vdb, particles_NNNN.vdb,
/// surface_NNNN.vdb, volume_NNNN.vdb, mesh_NNNN.ply/.obj,
/// field_lines_NNNN.ply/.obj, checkpoint_NNNN.lsck, stats.json,
/// contact_sheet.png, the manifest).
bool isRunOutput(const std::string& fileName);

}  // namespace lodestone::examples
