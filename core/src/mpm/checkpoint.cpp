// Checkpoints of the reference MLS-MPM; see mpm_checkpoint.h.
#include "lodestone/core/mpm/checkpoint.h"

#include <cmath>
#include <cstring>
#include <type_traits>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/hash.h"

namespace lodestone {
inline namespace mpm {

namespace {

constexpr char kMagic[8] = {'L', 'D', 'S', 'T', 'C', 'K', 'P', 'T'};
constexpr std::uint32_t kByteOrderMark = 0x01020304u;
constexpr std::size_t kHeaderSize = 8 + 4 + 4 + 8 + 8;
constexpr std::size_t kMaxTag = 64 * 1024;

class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>, "plain data only");
    const auto* b = reinterpret_cast<const std::uint8_t*>(&v);
    bytes.insert(bytes.end(), b, b + sizeof(T));
  }
  void putVec(const Vec3d& v) {
    put(v.x);
    put(v.y);
    put(v.z);
  }
  void putMat(const Mat3d& m) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) put(m(r, c));
  }
  void putGrid(const GridSpec& g) {
    putVec(g.origin);
    put(g.dx);
    put(std::int32_t(g.dims.i));
    put(std::int32_t(g.dims.j));
    put(std::int32_t(g.dims.k));
  }
  std::vector<std::uint8_t> bytes;
};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <typename T>
  T get(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>, "plain data only");
    need(sizeof(T), what);
    T v;
    std::memcpy(&v, data_ + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  Vec3d getVec(const char* what) {
    Vec3d v;
    v.x = get<double>(what);
    v.y = get<double>(what);
    v.z = get<double>(what);
    return v;
  }
  Mat3d getMat(const char* what) {
    Mat3d m;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m(r, c) = get<double>(what);
    return m;
  }
  GridSpec getGrid(const char* what) {
    GridSpec g;
    g.origin = getVec(what);
    g.dx = get<double>(what);
    g.dims.i = get<std::int32_t>(what);
    g.dims.j = get<std::int32_t>(what);
    g.dims.k = get<std::int32_t>(what);
    return g;
  }
  /// A count of items of `itemBytes` each that must fit in what is left.
  std::size_t getCount(std::size_t itemBytes, const char* what) {
    const std::uint64_t n = get<std::uint64_t>(what);
    if (itemBytes > 0 && n > (size_ - at_) / itemBytes)
      throw InvalidArgument(concat("checkpoint: ", what, " claims ", n, " entries of ", itemBytes, " bytes but only ",
                                   size_ - at_, " bytes are left (truncated or corrupted)"));
    return std::size_t(n);
  }
  std::string getString(std::size_t maxSize, const char* what) {
    const std::size_t n = getCount(1, what);
    if (n > maxSize) throw InvalidArgument(concat("checkpoint: ", what, " of ", n, " bytes exceeds ", maxSize));
    std::string s(reinterpret_cast<const char*>(data_ + at_), n);
    at_ += n;
    return s;
  }
  bool atEnd() const { return at_ == size_; }
  std::size_t left() const { return size_ - at_; }

 private:
  void need(std::size_t n, const char* what) const {
    if (n > size_ - at_)
      throw InvalidArgument(concat("checkpoint: the payload ends inside ", what, " (truncated or corrupted)"));
  }
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

// The payload after the header, checked; throws InvalidArgument otherwise.
Reader openPayload(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr && size > 0) throw InvalidArgument("checkpoint: no data (null pointer)");
  if (size < kHeaderSize)
    throw InvalidArgument(
        concat("checkpoint: ", size, " bytes is shorter than the ", kHeaderSize, "-byte header (truncated file?)"));
  if (std::memcmp(data, kMagic, 8) != 0)
    throw InvalidArgument("checkpoint: bad magic (not a Lodestone checkpoint, expected \"LDSTCKPT\")");
  std::uint32_t version = 0, bom = 0;
  std::uint64_t payload = 0, checksum = 0;
  std::memcpy(&version, data + 8, 4);
  std::memcpy(&bom, data + 12, 4);
  std::memcpy(&payload, data + 16, 8);
  std::memcpy(&checksum, data + 24, 8);
  if (bom != kByteOrderMark)
    throw InvalidArgument("checkpoint: written on a machine of the other byte order (byte-order mark mismatch)");
  if (version != kMpmCheckpointVersion)
    throw InvalidArgument(concat("checkpoint: format version ", version, " is not supported (this build reads ",
                                 kMpmCheckpointVersion, ")"));
  if (payload != size - kHeaderSize)
    throw InvalidArgument(concat("checkpoint: the header announces ", payload, " payload bytes but the file has ",
                                 size - kHeaderSize, " (truncated or corrupted)"));
  const std::uint64_t actual = fnv1a64(data + kHeaderSize, std::size_t(payload));
  if (actual != checksum)
    throw InvalidArgument(
        concat("checkpoint: checksum mismatch (stored ", checksum, ", computed ", actual, "): the file is corrupted"));
  return Reader(data + kHeaderSize, std::size_t(payload));
}

// The leading fields every payload starts with.
struct Head {
  std::string tag;
  std::int64_t frame = 0;
  double time = 0;
  long long substeps = 0;
};

Head readHead(Reader& r) {
  Head h;
  h.tag = r.getString(kMaxTag, "tag");
  h.frame = r.get<std::int64_t>("frame");
  h.time = r.get<double>("time");
  h.substeps = r.get<std::int64_t>("substep count");
  if (!std::isfinite(h.time)) throw InvalidArgument(concat("checkpoint: time is not finite (", h.time, " s)"));
  return h;
}

}  // namespace

// Friend of MpmSolver: reads and writes its private state.
struct MpmCheckpointAccess {
  static std::vector<std::uint8_t> save(const MpmSolver& s, std::int64_t frame, const std::string& tag) {
    require(tag.size() <= kMaxTag, "checkpoint: tag of ", tag.size(), " bytes exceeds ", kMaxTag);
    const MpmParticles& P = s.particles_;
    P.checkSizes();
    Writer w;
    w.put(std::uint64_t(tag.size()));
    w.bytes.insert(w.bytes.end(), tag.begin(), tag.end());
    w.put(std::int64_t(frame));
    w.put(s.time_);
    w.put(std::int64_t(s.substeps_));
    w.put(std::int32_t(s.stepsSinceSolve_));
    w.put(std::uint8_t(s.haveMagneticForce_));
    w.put(std::uint8_t(s.frameStart_));
    w.put(std::uint8_t(s.emittedSinceSort_));  // (version 2 wrote particlesDirty_ here, which restore never read)
    w.put(std::uint8_t(s.sameGrid_));
    w.putGrid(s.settings_.grid);
    w.putGrid(s.magneticGrid_);
    w.put(std::uint64_t(s.materials_.size()));
    w.put(std::uint64_t(s.colliders_.size()));
    w.put(std::uint64_t(s.magnets_.size()));
    for (const auto& m : s.magnets_) {
      w.putVec(m->pose().position);
      w.putMat(m->pose().rotation);
    }
    // The dynamic colliders' states and the material's pull on each magnet
    // at the last field solve (kept until the next).
    for (const MpmCollider& c : s.colliders_) {
      w.put(std::uint8_t(c.isDynamic()));
      if (!c.isDynamic()) continue;
      const ColliderState st = c.stateAt(s.time_);
      w.putVec(st.pose.position);
      w.putMat(st.pose.rotation);
      w.putVec(st.velocity);
      w.putVec(st.angularVelocity);
    }
    for (std::size_t m = 0; m < s.magnets_.size(); ++m) {
      const MagnetWrench r = m < s.magnetReaction_.size() ? s.magnetReaction_[m] : MagnetWrench{};
      w.putVec(r.force);
      w.putVec(r.torque);
    }
    w.putVec(s.magneticDropped_);

    const std::size_t n = P.size();
    w.put(std::uint64_t(n));
    w.put(std::uint64_t(P.nextId));
    for (std::size_t p = 0; p < n; ++p) w.putVec(P.x[p]);
    for (std::size_t p = 0; p < n; ++p) w.putVec(P.v[p]);
    for (std::size_t p = 0; p < n; ++p) w.putMat(P.C[p]);
    for (std::size_t p = 0; p < n; ++p) w.putMat(P.F[p]);
    for (std::size_t p = 0; p < n; ++p) w.put(P.J[p]);
    for (std::size_t p = 0; p < n; ++p) w.put(P.mass[p]);
    for (std::size_t p = 0; p < n; ++p) w.put(P.volume0[p]);
    for (std::size_t p = 0; p < n; ++p) w.put(P.count[p]);
    for (std::size_t p = 0; p < n; ++p) w.put(std::uint32_t(P.material[p]));
    for (std::size_t p = 0; p < n; ++p) w.put(std::uint64_t(P.id[p]));
    for (std::size_t p = 0; p < n; ++p) w.putVec(P.magneticForce[p]);

    const std::size_t nf = s.magneticForce_.empty() ? 0 : s.settings_.grid.nodeCount();
    w.put(std::uint64_t(nf));
    for (std::size_t i = 0; i < nf; ++i) w.putVec(s.magneticForce_.data()[i]);
    w.put(std::uint8_t(s.stage_ != nullptr));
    if (s.stage_) {
      w.putGrid(s.stage_->grid());
      const std::size_t nphi = s.stage_->grid().nodeCount();
      w.put(std::uint64_t(nphi));
      const GridView<const double> phi = s.stage_->potential();
      for (std::size_t i = 0; i < nphi; ++i) w.put(phi.data[i]);
    }
    // The planner's reuse test (positions and sampled applied field at the last solve).
    // A record of other particles than these (points emitted since the
    // solve) fails the reuse test as an empty one does, and is written empty:
    // restore accepts only a record of the particles it restores.
    const FieldReuse& reuse = s.reuse_;
    const bool current = reuse.positions().empty() || reuse.positions().size() == P.size();
    const auto putAll = [&](const auto& values, const auto& put) {
      w.put(std::uint64_t(current ? values.size() : 0));
      if (current)
        for (const auto& value : values) put(value);
    };
    putAll(reuse.positions(), [&](const Vec3d& x) { w.putVec(x); });
    putAll(reuse.fields(), [&](const Vec3d& H) { w.putVec(H); });
    putAll(reuse.samples(), [&](std::uint32_t q) { w.put(q); });

    std::vector<std::uint8_t> out(kHeaderSize + w.bytes.size());
    std::memcpy(out.data(), kMagic, 8);
    const std::uint32_t version = kMpmCheckpointVersion, bom = kByteOrderMark;
    const std::uint64_t payload = w.bytes.size(), checksum = fnv1a64(w.bytes.data(), w.bytes.size());
    std::memcpy(out.data() + 8, &version, 4);
    std::memcpy(out.data() + 12, &bom, 4);
    std::memcpy(out.data() + 16, &payload, 8);
    std::memcpy(out.data() + 24, &checksum, 8);
    if (!w.bytes.empty()) std::memcpy(out.data() + kHeaderSize, w.bytes.data(), w.bytes.size());
    return out;
  }

  static MpmCheckpointInfo restore(MpmSolver& s, const std::uint8_t* data, std::size_t size,
                                   const std::string& expectedTag) {
    Reader r = openPayload(data, size);
    const Head h = readHead(r);
    if (!expectedTag.empty() && h.tag != expectedTag)
      throw InvalidArgument(concat("checkpoint: it was written for '", h.tag, "', not for '", expectedTag,
                                   "' (a different scene or different options)"));
    const std::int32_t stepsSinceSolve = r.get<std::int32_t>("solve counter");
    const bool haveForce = r.get<std::uint8_t>("flags") != 0;
    const bool frameStart = r.get<std::uint8_t>("flags") != 0;
    const bool emittedSinceSort = r.get<std::uint8_t>("flags") != 0;
    const bool sameGrid = r.get<std::uint8_t>("flags") != 0;
    const GridSpec grid = r.getGrid("MPM grid"), mgrid = r.getGrid("magnetic grid");
    const auto equalGrids = [](const GridSpec& a, const GridSpec& b) {
      return a.origin.x == b.origin.x && a.origin.y == b.origin.y && a.origin.z == b.origin.z && a.dx == b.dx &&
             a.dims.i == b.dims.i && a.dims.j == b.dims.j && a.dims.k == b.dims.k;
    };
    if (!equalGrids(grid, s.settings_.grid) || !equalGrids(mgrid, s.magneticGrid_))
      throw InvalidArgument(concat("checkpoint: its grid (", grid.dims.i, " x ", grid.dims.j, " x ", grid.dims.k,
                                   " nodes, dx = ", grid.dx, " m) differs from the solver's (", s.settings_.grid.dims.i,
                                   " x ", s.settings_.grid.dims.j, " x ", s.settings_.grid.dims.k,
                                   " nodes, dx = ", s.settings_.grid.dx, " m) or its magnetic grid differs"));
    const std::uint64_t materials = r.get<std::uint64_t>("material count");
    const std::uint64_t colliders = r.get<std::uint64_t>("collider count");
    const std::uint64_t magnets = r.get<std::uint64_t>("magnet count");
    if (materials != s.materials_.size() || colliders != s.colliders_.size() || magnets != s.magnets_.size())
      throw InvalidArgument(concat("checkpoint: it holds ", materials, " materials, ", colliders, " colliders and ",
                                   magnets, " magnets; the solver has ", s.materials_.size(), ", ", s.colliders_.size(),
                                   " and ", s.magnets_.size()));
    std::vector<Pose> poses(magnets);
    for (Pose& p : poses) {
      p.position = r.getVec("magnet pose");
      p.rotation = r.getMat("magnet pose");
      bool finite = isFinite(p.position);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) finite = finite && std::isfinite(p.rotation(i, j));
      if (!finite) throw InvalidArgument("checkpoint: a magnet pose is not finite");
    }
    std::vector<ColliderState> bodies(colliders);
    for (std::size_t c = 0; c < colliders; ++c) {
      const bool dynamic = r.get<std::uint8_t>("collider kind") != 0;
      if (dynamic != s.colliders_[c].isDynamic())
        throw InvalidArgument(concat("checkpoint: collider ", c, " is ", dynamic ? "dynamic" : "kinematic",
                                     " in it and ", dynamic ? "kinematic" : "dynamic", " in the solver"));
      if (!dynamic) continue;
      ColliderState& st = bodies[c];
      st.pose.position = r.getVec("rigid body pose");
      st.pose.rotation = r.getMat("rigid body pose");
      st.velocity = r.getVec("rigid body velocity");
      st.angularVelocity = r.getVec("rigid body angular velocity");
      validatePose(st.pose, "checkpoint: rigid body");
      if (!isFinite(st.velocity) || !isFinite(st.angularVelocity))
        throw InvalidArgument(concat("checkpoint: rigid body ", c, " has a non-finite velocity"));
    }
    std::vector<MagnetWrench> reactions(magnets);
    for (MagnetWrench& m : reactions) {
      m.force = r.getVec("magnet reaction");
      m.torque = r.getVec("magnet reaction");
    }
    const Vec3d dropped = r.getVec("dropped magnetic force");

    const std::size_t perParticle = 3 * 8 * 2 + 9 * 8 * 2 + 4 * 8 + 4 + 8 + 3 * 8;
    const std::size_t n = r.getCount(perParticle, "particle count");
    MpmParticles P;
    P.nextId = r.get<std::uint64_t>("next particle id");
    P.x.resize(n);
    P.v.resize(n);
    P.C.resize(n);
    P.F.resize(n);
    P.J.resize(n);
    P.mass.resize(n);
    P.volume0.resize(n);
    P.count.resize(n);
    P.material.resize(n);
    P.id.resize(n);
    P.magneticForce.resize(n);
    for (std::size_t p = 0; p < n; ++p) P.x[p] = r.getVec("positions");
    for (std::size_t p = 0; p < n; ++p) P.v[p] = r.getVec("velocities");
    for (std::size_t p = 0; p < n; ++p) P.C[p] = r.getMat("APIC matrices");
    for (std::size_t p = 0; p < n; ++p) P.F[p] = r.getMat("deformation gradients");
    for (std::size_t p = 0; p < n; ++p) P.J[p] = r.get<double>("volume ratios");
    for (std::size_t p = 0; p < n; ++p) P.mass[p] = r.get<double>("masses");
    for (std::size_t p = 0; p < n; ++p) P.volume0[p] = r.get<double>("rest volumes");
    for (std::size_t p = 0; p < n; ++p) P.count[p] = r.get<double>("micro-particle counts");
    for (std::size_t p = 0; p < n; ++p) {
      P.material[p] = r.get<std::uint32_t>("materials");
      if (P.material[p] >= materials)
        throw InvalidArgument(concat("checkpoint: particle ", p, " has material ", P.material[p], " of ", materials));
    }
    for (std::size_t p = 0; p < n; ++p) P.id[p] = r.get<std::uint64_t>("ids");
    for (std::size_t p = 0; p < n; ++p) P.magneticForce[p] = r.getVec("per-particle magnetic forces");
    for (std::size_t p = 0; p < n; ++p) {
      // What a solver could never have written: refuse rather than step it.
      bool finiteMatrices = true;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          finiteMatrices = finiteMatrices && std::isfinite(P.C[p](i, j)) && std::isfinite(P.F[p](i, j));
      if (!isFinite(P.x[p]) || !isFinite(P.v[p]) || !finiteMatrices || !isFinite(P.magneticForce[p]) ||
          !(std::isfinite(P.J[p]) && P.J[p] > 0) || !(std::isfinite(P.mass[p]) && P.mass[p] > 0) ||
          !(std::isfinite(P.volume0[p]) && P.volume0[p] > 0) || !(std::isfinite(P.count[p]) && P.count[p] >= 0))
        throw InvalidArgument(concat("checkpoint: particle ", p, " has a non-finite or non-physical state (mass ",
                                     P.mass[p], " kg, V0 ", P.volume0[p], " m^3, n_p ", P.count[p], ", J ", P.J[p],
                                     ")"));
    }

    const std::size_t nf = r.getCount(24, "magnetic nodal force");
    if (nf != 0 && nf != s.settings_.grid.nodeCount())
      throw InvalidArgument(concat("checkpoint: magnetic nodal force of ", nf, " nodes does not fit the MPM grid (",
                                   s.settings_.grid.nodeCount(), " nodes)"));
    std::vector<Vec3d> force(nf);
    for (Vec3d& f : force) f = r.getVec("magnetic nodal force");
    const bool hasStage = r.get<std::uint8_t>("stage flag") != 0;
    GridSpec stageGrid;
    if (hasStage) {
      stageGrid = r.getGrid("stage grid");
      stageGrid.validate("checkpoint: stage grid");
      const GridSpec& m = s.magneticGrid_;
      const int sd[3] = {stageGrid.dims.i, stageGrid.dims.j, stageGrid.dims.k};
      const int md[3] = {m.dims.i, m.dims.j, m.dims.k};
      for (int a = 0; a < 3; ++a) {
        const double lo = (stageGrid.origin[a] - m.origin[a]) / m.dx;
        if (stageGrid.dx != m.dx || !(lo > -1e-6) || !(lo + sd[a] - 1 < md[a] - 1 + 1e-6))
          throw InvalidArgument("checkpoint: the stage grid is not inside the magnetic grid");
      }
      const std::size_t nphi = r.getCount(8, "potential");
      if (nphi != stageGrid.nodeCount())
        throw InvalidArgument(concat("checkpoint: potential of ", nphi, " nodes does not fit its stage grid (",
                                     stageGrid.nodeCount(), " nodes)"));
      for (std::size_t i = 0; i < nphi; ++i) (void)r.get<double>("potential");
    }
    std::vector<Vec3d> lastX(r.getCount(24, "planner positions"));
    for (Vec3d& x : lastX) x = r.getVec("planner positions");
    std::vector<Vec3d> lastH(r.getCount(24, "planner fields"));
    for (Vec3d& H : lastH) H = r.getVec("planner fields");
    std::vector<std::uint32_t> lastSample(r.getCount(4, "planner samples"));
    for (std::uint32_t& q : lastSample) {
      q = r.get<std::uint32_t>("planner samples");
      if (q >= n) throw InvalidArgument(concat("checkpoint: planner sample ", q, " of ", n, " particles"));
    }
    if ((!lastX.empty() && lastX.size() != n) || lastH.size() != lastSample.size())
      throw InvalidArgument("checkpoint: the planner's records do not match the particles");
    if (!r.atEnd()) throw InvalidArgument(concat("checkpoint: ", r.left(), " unexpected bytes after the payload"));

    // Everything parsed: change the solver.
    s.particles_ = std::move(P);
    s.keepOwnedParticles(0);  // with a partition: every process reads the same file, each keeps its own
    s.time_ = h.time;
    s.substeps_ = h.substeps;
    s.stepsSinceSolve_ = stepsSinceSolve;
    s.haveMagneticForce_ = haveForce;
    s.frameStart_ = frameStart;
    // A domain check at the next substep: a no-op for particles the solver
    // wrote (they are inside), a clamp or removal for any that are not.
    s.particlesDirty_ = true;
    // Points emitted since the last sort: the next substep sorts them (in an
    // older file this byte was the dirty mark: at worst one more sort of the
    // particles by cell).
    s.emittedSinceSort_ = emittedSinceSort;
    s.magneticDropped_ = dropped;
    for (std::size_t m = 0; m < poses.size(); ++m) s.magnets_[m]->setPose(poses[m]);
    for (std::size_t c = 0; c < bodies.size(); ++c)
      if (s.colliders_[c].isDynamic())
        s.colliders_[c].setMotion(ColliderMotion::dynamic(bodies[c].pose, bodies[c].velocity, bodies[c].angularVelocity));
    s.magnetReaction_ = std::move(reactions);
    s.sameGrid_ = sameGrid;
    if (nf > 0) {
      if (s.magneticForce_.empty() || !(s.magneticForce_.spec() == s.settings_.grid))
        s.magneticForce_.reset(s.settings_.grid, Vec3d{});
      std::copy(force.begin(), force.end(), s.magneticForce_.data());
    } else if (!s.magneticForce_.empty()) {
      s.magneticForce_.fill(Vec3d{});
    }
    s.reuse_.restore(std::move(lastX), std::move(lastSample), std::move(lastH));
    // The stage on its saved grid with phi = 0: what the saving run has after
    // MpmSolver::resetMagneticWarmStart (see the header).
    s.stage_.reset();
    if (hasStage) {
      const MagneticMaterial* law = nullptr;
      for (const MpmMaterial& m : s.materials_)
        if (m.isMagnetic() && !law) law = &m.magnetic;
      if (law) s.stage_ = std::make_unique<MagneticForceStage>(stageGrid, *law, s.settings_.magnetic);
    }
    return MpmCheckpointInfo{kMpmCheckpointVersion, h.frame, h.time, h.substeps, n, h.tag};
  }
};

std::vector<std::uint8_t> saveMpmCheckpoint(const MpmSolver& solver, std::int64_t frame, const std::string& tag) {
  return MpmCheckpointAccess::save(solver, frame, tag);
}

MpmCheckpointInfo readMpmCheckpointInfo(const std::uint8_t* data, std::size_t size) {
  Reader r = openPayload(data, size);
  const Head h = readHead(r);
  MpmCheckpointInfo info;
  info.version = kMpmCheckpointVersion;
  info.frame = h.frame;
  info.time = h.time;
  info.substeps = h.substeps;
  info.tag = h.tag;
  (void)r.get<std::int32_t>("solve counter");
  for (int f = 0; f < 4; ++f) (void)r.get<std::uint8_t>("flags");
  (void)r.getGrid("MPM grid");
  (void)r.getGrid("magnetic grid");
  (void)r.get<std::uint64_t>("material count");
  const std::uint64_t colliders = r.get<std::uint64_t>("collider count");
  const std::uint64_t magnets = r.get<std::uint64_t>("magnet count");
  for (std::uint64_t m = 0; m < magnets; ++m) {
    (void)r.getVec("magnet pose");
    (void)r.getMat("magnet pose");
  }
  for (std::uint64_t c = 0; c < colliders; ++c) {
    if (r.get<std::uint8_t>("collider kind") == 0) continue;
    (void)r.getVec("rigid body pose");
    (void)r.getMat("rigid body pose");
    (void)r.getVec("rigid body velocity");
    (void)r.getVec("rigid body angular velocity");
  }
  for (std::uint64_t m = 0; m < 2 * magnets; ++m) (void)r.getVec("magnet reaction");
  (void)r.getVec("dropped magnetic force");
  info.particles = r.getCount(1, "particle count");
  return info;
}

MpmCheckpointInfo restoreMpmCheckpoint(MpmSolver& solver, const std::uint8_t* data, std::size_t size,
                                       const std::string& expectedTag) {
  return MpmCheckpointAccess::restore(solver, data, size, expectedTag);
}

}  // namespace mpm
}  // namespace lodestone
