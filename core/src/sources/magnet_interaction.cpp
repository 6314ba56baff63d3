#include "lodestone/core/sources/magnet_interaction.h"

#include <cmath>
#include <vector>

#include "lodestone/core/base/error.h"
#include "lodestone/core/base/gauss_legendre.h"
#include "lodestone/core/sources/cuboid_magnet.h"
#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/sources/sphere_magnet.h"

namespace lodestone {
inline namespace sources {
namespace {

/// A surface quadrature point: world position (m) and charge sigma dA (A*m),
/// time scaling included.
struct SurfaceCharge {
  Vec3d x;
  double q;
};

std::string vecText(const Vec3d& v) { return concat("(", v.x, ", ", v.y, ", ", v.z, ")"); }

/// Quadrature of the surface charges sigma = s(t) M.n of `m` (body-frame
/// rule mapped to the world frame). Throws for an unknown shape.
std::vector<SurfaceCharge> surfaceCharges(const MagnetSource& m, double t, int order) {
  std::vector<double> gx, gw;
  gaussLegendreRule(order, gx, gw);
  const std::size_t n = gx.size();
  const Vec3d M = m.bodyMagnetization() * m.profile()(t);
  const Pose& pose = m.pose();
  std::vector<SurfaceCharge> out;
  const auto add = [&](const Vec3d& xBody, const Vec3d& nBody, double dA) {
    out.push_back({pose.toWorld(xBody), dot(M, nBody) * dA});
  };
  if (const auto* box = dynamic_cast<const CuboidMagnet*>(&m)) {
    const Vec3d h = box->halfSize();
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const double jac = h[i] * h[j];
      for (double side : {-1.0, 1.0}) {
        Vec3d nBody;
        nBody[k] = side;
        for (std::size_t p = 0; p < n; ++p)
          for (std::size_t q = 0; q < n; ++q) {
            Vec3d x;
            x[k] = side * h[k];
            x[i] = h[i] * gx[p];
            x[j] = h[j] * gx[q];
            add(x, nBody, jac * gw[p] * gw[q]);
          }
      }
    }
  } else if (const auto* cyl = dynamic_cast<const CylinderMagnet*>(&m)) {
    const double R = cyl->radius(), L = cyl->halfLength();
    const std::size_t na = 2 * n;
    for (double side : {-1.0, 1.0})
      for (std::size_t p = 0; p < n; ++p) {
        const double rho = 0.5 * R * (gx[p] + 1);
        const double wr = 0.5 * R * gw[p] * rho * (2.0 * kPi / double(na));
        for (std::size_t a = 0; a < na; ++a) {
          const double phi = 2.0 * kPi * (double(a) + 0.5) / double(na);
          add({rho * std::cos(phi), rho * std::sin(phi), side * L}, {0, 0, side}, wr);
        }
      }
  } else if (const auto* sph = dynamic_cast<const SphereMagnet*>(&m)) {
    const double R = sph->radius();
    const std::size_t na = 2 * n;
    for (std::size_t p = 0; p < n; ++p) {
      const double c = gx[p], s = std::sqrt(1 - c * c);
      const double w = R * R * gw[p] * (2.0 * kPi / double(na));
      for (std::size_t a = 0; a < na; ++a) {
        const double phi = 2.0 * kPi * (double(a) + 0.5) / double(na);
        const Vec3d nBody{s * std::cos(phi), s * std::sin(phi), c};
        add(R * nBody, nBody, w);
      }
    }
  } else {
    throw InvalidArgument(concat("magnet interaction: the surface-charge method needs a sphere, "
                                 "cuboid or cylinder magnet, got ",
                                 m.describe()));
  }
  return out;
}

/// Throws unless `other`'s centre and every point of `charges` lie outside `m`
/// (the message is built only on failure).
void requireOutside(const MagnetSource& m, const MagnetSource& other,
                    const std::vector<SurfaceCharge>& charges) {
  const auto check = [&](const Vec3d& x) {
    if (m.containsBody(m.pose().toLocal(x)))
      throw InvalidArgument(concat("magnet interaction: the bodies overlap: the point ",
                                   vecText(x), " m lies inside ", m.describe()));
  };
  check(other.pose().position);
  for (const SurfaceCharge& c : charges) check(c.x);
}

}  // namespace

MagnetWrench magnetInteraction(const MagnetSource& a, const MagnetSource& b, double t,
                               MagnetInteractionMethod method, int order) {
  const Vec3d xa = a.pose().position, xb = b.pose().position;
  const Vec3d r = xb - xa;
  require(norm2(r) > 0, "magnet interaction: coincident centres ", vecText(xa), " m and ",
          vecText(xb), " m");
  require(order >= 1 && order <= 256,
          "magnet interaction: quadrature order must be in [1, 256], got ", order);
  const auto* sa = dynamic_cast<const SphereMagnet*>(&a);
  const auto* sb = dynamic_cast<const SphereMagnet*>(&b);
  if (sa && sb) {
    const double d = norm(r);
    require(d >= sa->radius() + sb->radius(), "magnet interaction: the spheres overlap: centre distance ",
            d, " m < radii ", sa->radius(), " m + ", sb->radius(), " m (centres ", vecText(xa),
            " m, ", vecText(xb), " m)");
  }
  if (method == MagnetInteractionMethod::Dipole) {
    if (!(sa && sb)) {
      // Overlap check at the rule of `order` (the field is not needed).
      requireOutside(a, b, surfaceCharges(b, t, order));
      requireOutside(b, a, surfaceCharges(a, t, order));
    }
    const Vec3d ma = a.moment(t), mb = b.moment(t);
    return {dipoleDipoleForce(ma, mb, r), dipoleDipoleTorque(ma, mb, r)};
  }
  const std::vector<SurfaceCharge> charges = surfaceCharges(b, t, order);
  if (!(sa && sb)) {
    requireOutside(a, b, charges);
    requireOutside(b, a, surfaceCharges(a, t, order));
  }
  MagnetWrench w{};
  for (const SurfaceCharge& c : charges) {
    const Vec3d dF = (kMu0 * c.q) * a.field(c.x, t);
    w.force += dF;
    w.torque += cross(c.x - xb, dF);
  }
  return w;
}

}  // namespace sources
}  // namespace lodestone
