// Emission over time; see mpm/rate_emitter.h.
#include "lodestone/core/mpm/rate_emitter.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "lodestone/core/base/error.h"

namespace lodestone {
inline namespace mpm {

// ---------------------------------------------------------------------------
// Time line

EmissionSchedule EmissionSchedule::between(double start, double end) { return intervals({{start, end}}); }

EmissionSchedule EmissionSchedule::intervals(std::vector<std::pair<double, double>> onOff) {
  require(!onOff.empty(), "emitter time line: at least one on/off interval is needed");
  for (std::size_t i = 0; i < onOff.size(); ++i) {
    const double on = onOff[i].first, off = onOff[i].second;
    require(std::isfinite(on) && on >= 0, "emitter time line: interval ", i, " starts at ", on,
            " s; a start must be a finite time >= 0 s");
    require(!std::isnan(off) && off > on, "emitter time line: interval ", i, " ends at ", off,
            " s, not after its start ", on, " s");
    if (i > 0) {  // (require evaluates its message's arguments even when the check holds)
      const double previousOff = onOff[i - 1].second;
      require(on >= previousOff, "emitter time line: interval ", i, " starts at ", on, " s, before interval ", i - 1,
              " ends (", previousOff, " s)");
    }
    onOff[i].second = std::min(off, kForever);
  }
  EmissionSchedule s;
  s.intervals_ = std::move(onOff);
  return s;
}

double EmissionSchedule::activeTime(double t) const {
  double a = 0;
  for (const auto& [on, off] : intervals_) {
    if (t <= on) break;
    a += std::min(t, off) - on;
  }
  return a;
}

double EmissionSchedule::timeAtActive(double active) const {
  double a = 0;
  for (const auto& [on, off] : intervals_) {
    const double length = off - on;
    if (active < a + length) return on + (active - a);
    a += length;
  }
  return kForever;
}

bool EmissionSchedule::isOn(double t) const {
  for (const auto& [on, off] : intervals_)
    if (t >= on && t < off) return true;
  return false;
}

bool EmissionSchedule::onWithin(double t0, double t1) const {
  for (const auto& [on, off] : intervals_)
    if (on < t1 && off > t0) return true;
  return false;
}

// ---------------------------------------------------------------------------
// Settings and reports

const char* toString(EmissionRateKind kind) {
  switch (kind) {
    case EmissionRateKind::VolumePerSecond:
      return "volume";
    case EmissionRateKind::ParticlesPerSecond:
      return "particles";
    case EmissionRateKind::Stream:
      return "stream";
  }
  return "unknown";
}

void RateEmitterSettings::validate() const {
  require(rateKind == EmissionRateKind::VolumePerSecond || rateKind == EmissionRateKind::ParticlesPerSecond ||
              rateKind == EmissionRateKind::Stream,
          "emitter: unknown rate kind ", int(rateKind));
  if (rateKind != EmissionRateKind::Stream)
    require(std::isfinite(rate) && rate > 0, "emitter: rate must be positive and finite (",
            rateKind == EmissionRateKind::VolumePerSecond ? "m^3/s" : "particles/s", "), got ", rate);
  lattice.validate();
  require(norm2(lattice.angularVelocity) == 0, "emitter: an emitted stream takes no angular velocity, got (",
          lattice.angularVelocity.x, ", ", lattice.angularVelocity.y, ", ", lattice.angularVelocity.z, ") rad/s");
  require(maxParticlesPerStep > 0, "emitter: maxParticlesPerStep must be positive");
}

RateEmitReport& RateEmitReport::operator+=(const RateEmitReport& o) {
  chunks += o.chunks;
  particles += o.particles;
  blocked += o.blocked;
  outside += o.outside;
  volume += o.volume;
  mass += o.mass;
  return *this;
}

// ---------------------------------------------------------------------------
// The emitter

RateEmitter::RateEmitter(const EmitterShape& shape, const RateEmitterSettings& settings, const MpmMaterial& material,
                         std::uint32_t materialIndex)
    : shape_(shape), settings_(settings), materialIndex_(materialIndex) {
  settings_.validate();
  material.validate();
  lattice_ = emitterLattice(shape_, settings_.lattice);
  require(!lattice_.points.empty(), "emitter: the shape holds no lattice point at a spacing of ", lattice_.spacing.x,
          " m; use a larger shape or more particles per cell");
  point_ = emittedPoint(material, lattice_.pointVolume);
  switch (settings_.rateKind) {
    case EmissionRateKind::VolumePerSecond:
      rate_ = settings_.rate;
      break;
    case EmissionRateKind::ParticlesPerSecond:
      rate_ = settings_.rate * point_.volume;
      break;
    case EmissionRateKind::Stream: {
      const double speed = settings_.velocityInBodyFrame ? settings_.lattice.velocity.z : 0.0;
      require(speed > 0,
              "emitter: a stream rate needs a positive speed along the emitter's axis (velocity in the body frame, "
              "m/s), got ",
              speed, settings_.velocityInBodyFrame ? "" : " (the velocity is given in the world frame)");
      rate_ = speed * chunkVolume() / (lattice_.cells.k * lattice_.spacing.z);
      break;
    }
  }
  require(std::isfinite(chunkPeriod()) && chunkPeriod() > 0, "emitter: a rate of ", rate_,
          " m^3/s gives no finite chunk period for a chunk of ", chunkVolume(), " m^3");
}

Pose RateEmitter::poseAt(double t) const { return settings_.followsMotion ? settings_.motion.poseAt(t) : shape_.pose; }

long long RateEmitter::chunksBy(double t) const {
  const double a = settings_.schedule.activeTime(t);
  if (!(a > 0)) return 0;
  const double n = std::ceil(a / chunkPeriod());
  return n < 4e18 ? (long long)n : (long long)4e18;
}

double RateEmitter::birthTime(long long k) const { return settings_.schedule.timeAtActive(double(k) * chunkPeriod()); }

Vec3d RateEmitter::velocityAt(const Pose& pose, const Vec3d& x, double t) const {
  const Vec3d& u = settings_.lattice.velocity;
  Vec3d v = settings_.velocityInBodyFrame ? pose.rotation * u : u;
  if (settings_.inheritMotion && settings_.followsMotion) {
    Vec3d linear, angular;
    settings_.motion.velocityAt(t, linear, angular);
    v += linear + cross(angular, x - pose.position);
  }
  return v;
}

double RateEmitter::emissionSpeed(double t0, double t1) const {
  if (!settings_.schedule.onWithin(t0, t1)) return 0;
  double speed = norm(settings_.lattice.velocity);
  if (settings_.inheritMotion && settings_.followsMotion) {
    double reach = 0;  // farthest lattice point from the body origin, m
    for (const Vec3d& xb : lattice_.points) reach = std::max(reach, norm(xb));
    Vec3d linear, angular;
    settings_.motion.velocityAt(t0, linear, angular);
    speed += norm(linear) + norm(angular) * reach;
  }
  return speed;
}

namespace {
// Cells of the full-space test: a hash of integer cell coordinates (collisions
// only cost time, the distance test is exact).
struct CellHash {
  std::size_t operator()(std::uint64_t key) const { return std::size_t(key * 0x9E3779B97F4A7C15ull >> 17); }
};
std::uint64_t cellKey(long long i, long long j, long long k) {
  return std::uint64_t(i) * 73856093ull ^ std::uint64_t(j) * 19349663ull ^ std::uint64_t(k) * 83492791ull;
}
}  // namespace

RateEmitReport RateEmitter::emitBetween(MpmParticles& particles, double t0, double t1,
                                        const ParticleBounds& bounds) const {
  RateEmitReport rep;
  const long long n0 = chunksBy(t0), n1 = chunksBy(t1);
  if (n1 <= n0) return rep;
  const double due = double(n1 - n0) * double(chunkParticles());
  require(due <= double(settings_.maxParticlesPerStep), "emitter: ", due, " particles are due in one substep (",
          n1 - n0, " chunks of ", chunkParticles(), " in ", t1 - t0, " s at ", rate_,
          " m^3/s), more than the limit of ", settings_.maxParticlesPerStep,
          " a substep; lower the rate or the particles per cell, or shorten the time step");
  particles.checkSizes();

  // Candidates: each chunk at its birth pose, moved by its emission velocity
  // for the rest of the substep.
  struct Candidate {
    Vec3d x, v;
    long long chunk;
  };
  std::vector<Candidate> candidates;
  candidates.reserve(std::size_t(due));
  for (long long k = n0; k < n1; ++k) {
    const double tk = std::clamp(birthTime(k), t0, t1);
    const Pose pose = poseAt(tk);
    EmitterLattice jittered;
    if (settings_.lattice.jitter > 0) {
      EmitterSettings s = settings_.lattice;
      s.seed ^= 0x9E3779B97F4A7C15ull * std::uint64_t(k + 1);  // its own, reproducible jitter per chunk
      jittered = emitterLattice(shape_, s);
    }
    const std::vector<Vec3d>& points = settings_.lattice.jitter > 0 ? jittered.points : lattice_.points;
    for (const Vec3d& xb : points) {
      const Vec3d x = pose.toWorld(xb);
      const Vec3d v = velocityAt(pose, x, tk);
      candidates.push_back({x + (t1 - tk) * v, v, k});
    }
  }
  rep.chunks = n1 - n0;

  // Full space: material within r of a candidate, r = 0.9 h (a point there
  // would compress the material by more than 1/0.9^3 = 1.37), less by the
  // jitter that may bring lattice neighbours closer.
  const double h = std::min({lattice_.spacing.x, lattice_.spacing.y, lattice_.spacing.z});
  const double r = 0.9 * h * (1 - settings_.lattice.jitter);
  Vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const Candidate& c : candidates)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c.x[a] - r), hi[a] = std::max(hi[a], c.x[a] + r);
  const double cell = r > 0 ? r : 1.0;
  const auto cellOf = [&](const Vec3d& x, int a) { return (long long)std::floor((x[a] - lo[a]) / cell); };
  std::unordered_map<std::uint64_t, std::vector<std::size_t>, CellHash> occupied;
  std::vector<long long> chunkOf;  // chunk of each particle added here (-1: older material)
  const auto insert = [&](std::size_t p) {
    occupied[cellKey(cellOf(particles.x[p], 0), cellOf(particles.x[p], 1), cellOf(particles.x[p], 2))].push_back(p);
  };
  const std::size_t before = particles.size();
  if (r > 0)
    for (std::size_t p = 0; p < before; ++p) {
      const Vec3d& x = particles.x[p];
      if (x.x >= lo.x && x.x <= hi.x && x.y >= lo.y && x.y <= hi.y && x.z >= lo.z && x.z <= hi.z) insert(p);
    }
  const auto full = [&](const Candidate& c) {
    if (!(r > 0)) return false;
    const long long ci = cellOf(c.x, 0), cj = cellOf(c.x, 1), ck = cellOf(c.x, 2);
    for (long long k = ck - 1; k <= ck + 1; ++k)
      for (long long j = cj - 1; j <= cj + 1; ++j)
        for (long long i = ci - 1; i <= ci + 1; ++i) {
          const auto it = occupied.find(cellKey(i, j, k));
          if (it == occupied.end()) continue;
          for (const std::size_t p : it->second) {
            // Points of the same chunk are lattice neighbours, never in each other's way.
            if (p >= before && chunkOf[p - before] == c.chunk) continue;
            if (norm2(particles.x[p] - c.x) < r * r) return true;
          }
        }
    return false;
  };
  for (const Candidate& c : candidates) {
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && c.x[a] >= bounds.lo[a] && c.x[a] <= bounds.hi[a];
    if (!inside) {
      ++rep.outside;
      continue;
    }
    if (full(c)) {
      ++rep.blocked;
      continue;
    }
    const std::size_t q = particles.add(c.x, c.v, point_.mass, point_.volume, point_.count, materialIndex_);
    chunkOf.push_back(c.chunk);
    if (r > 0) insert(q);
    rep.volume += point_.volume;
    rep.mass += point_.mass;
  }
  rep.particles = particles.size() - before;
  return rep;
}

std::string RateEmitter::describe() const {
  std::ostringstream os;
  os.precision(4);
  const char* shapes[] = {"box", "sphere", "cylinder", "level set"};
  os << shapes[int(shape_.kind)] << ", " << volumeRate() << " m^3/s (" << toString(settings_.rateKind) << "), "
     << chunkParticles() << " points (" << chunkVolume() << " m^3) every " << chunkPeriod() << " s of on-time, on";
  for (const auto& [on, off] : settings_.schedule.list()) {
    os << " [" << on << ", ";
    if (off >= EmissionSchedule::kForever)
      os << "end)";
    else
      os << off << ")";
  }
  os << " s";
  return os.str();
}

}  // namespace mpm
}  // namespace lodestone
