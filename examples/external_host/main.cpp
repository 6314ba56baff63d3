// An independent MPM-like host that uses Lodestone only through its C ABI.
//
// It includes nothing but <lodestone/plugin/lodestone.h>, links nothing of
// Lodestone, and dlopen()s liblodestone_plugin.so at run time. It keeps its
// own particles (an array of structs, handed to the plugin with strides) and
// its own MLS-MPM grid, whose spacing and origin differ from the magnetic
// stage's grid, so it takes the stage's conservative per-particle forces and
// deposits them in its P2G. The scene: an elastic ball of magnetic material
// (the paper's Langevin law) pulled toward a cylindrical magnet below it, in
// free space (no gravity). It writes a JSON summary: the setup and the ball's
// centre-of-mass trajectory per frame.
//
// Usage: lodestone-external-host [--plugin PATH] [--out FILE.json] [--frames N]
#include <dlfcn.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "lodestone/plugin/lodestone.h"

#ifndef LODESTONE_PLUGIN_DEFAULT_PATH
#define LODESTONE_PLUGIN_DEFAULT_PATH "liblodestone_plugin.so"
#endif

namespace {

// ---- the setup (written to the summary so a reference can rebuild it) ----
struct Setup {
  double ballCenter[3] = {0.0, 0.0, 0.025};  // m
  double ballRadius = 0.016;                 // m
  double particleSpacing = 0.004;            // m, lattice of material points
  double density = 1000.0;                   // kg/m^3
  double youngsModulus = 2e5;                // Pa
  double poissonRatio = 0.3;
  double magnetCenter[3] = {0.0, 0.0, -0.03};  // m, magnetized along +z
  double magnetRadius = 0.02;                  // m
  double magnetHalfLength = 0.01;              // m
  double magnetization = 8e5;                  // A/m
  // The magnetic stage's grid (before padding): the host chooses it.
  double stageOrigin[3] = {-0.05, -0.05, -0.015};  // m
  double stageDx = 0.004;                          // m
  int stageDims[3] = {26, 26, 22};
  int stagePadding = 2;
  double tolerance = 1e-7;
  // The host's own MPM grid: another spacing and origin.
  double hostOrigin[3] = {-0.0731, -0.0729, -0.0387};  // m
  double hostDx = 0.0061;                              // m
  int hostDims[3] = {25, 25, 24};
  double dt = 1e-4;  // s
  double fps = 400;  // frames per second; one field solve per frame
  int frames = 12;
};

struct Particle {  // the host's own storage (array of structs)
  double x[3], v[3];
  double C[9], F[9];
  double mass, volume0;
  double count;  // micro-particles n_p
};

void matMul(const double* a, const double* b, double* out) {
  double r[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
  std::memcpy(out, r, sizeof r);
}

double det(const double* a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/// Inverse transpose of a (3x3, row-major).
void invT(const double* a, double* out) {
  const double d = det(a);
  // cofactor matrix / det = inverse transpose
  out[0] = (a[4] * a[8] - a[5] * a[7]) / d;
  out[1] = -(a[3] * a[8] - a[5] * a[6]) / d;
  out[2] = (a[3] * a[7] - a[4] * a[6]) / d;
  out[3] = -(a[1] * a[8] - a[2] * a[7]) / d;
  out[4] = (a[0] * a[8] - a[2] * a[6]) / d;
  out[5] = -(a[0] * a[7] - a[1] * a[6]) / d;
  out[6] = (a[1] * a[5] - a[2] * a[4]) / d;
  out[7] = -(a[0] * a[5] - a[2] * a[3]) / d;
  out[8] = (a[0] * a[4] - a[1] * a[3]) / d;
}

struct Api {
  void* lib = nullptr;
  const lodestone_api* api = nullptr;
  lodestone_context* ctx = nullptr;
};

[[noreturn]] void die(const std::string& message) {
  std::fprintf(stderr, "lodestone-external-host: %s\n", message.c_str());
  std::exit(1);
}

void check(const Api& a, lodestone_status s, const char* what) {
  if (s == LODESTONE_OK) return;
  const char* message = a.ctx ? a.api->context_last_error(a.ctx) : a.api->thread_last_error();
  die(std::string(what) + " failed (" + a.api->status_string(s) + "): " + message);
}

/// Quadratic B-spline weights and base node along one axis.
void weights(double u, int& base, double w[3], double& fx) {
  base = int(std::floor(u - 0.5));
  fx = u - base;
  w[0] = 0.5 * (1.5 - fx) * (1.5 - fx);
  w[1] = 0.75 - (fx - 1.0) * (fx - 1.0);
  w[2] = 0.5 * (fx - 0.5) * (fx - 0.5);
}

}  // namespace

int main(int argc, char** argv) {
  std::string pluginPath = LODESTONE_PLUGIN_DEFAULT_PATH, outPath = "external_host.json";
  Setup s;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--plugin" && i + 1 < argc)
      pluginPath = argv[++i];
    else if (a == "--out" && i + 1 < argc)
      outPath = argv[++i];
    else if (a == "--frames" && i + 1 < argc)
      s.frames = std::atoi(argv[++i]);
    else
      die("usage: lodestone-external-host [--plugin PATH] [--out FILE.json] [--frames N]; got '" + a + "'");
  }
  if (s.frames < 1) die("--frames must be >= 1");

  // ---- load the plugin: one symbol, a versioned table ----
  Api a;
  a.lib = dlopen(pluginPath.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!a.lib) die(std::string("cannot load ") + pluginPath + ": " + dlerror());
  auto getApi = reinterpret_cast<lodestone_get_api_fn>(dlsym(a.lib, "lodestone_get_api"));
  if (!getApi) die("lodestone_get_api not found in " + pluginPath);
  if (getApi(LODESTONE_API_VERSION_MAJOR, LODESTONE_API_VERSION_MINOR, &a.api) != LODESTONE_OK)
    die("version refused");  // no table: no thread_last_error to ask
  check(a, a.api->context_create(&a.ctx), "context_create");

  // ---- the stage: its own grid, the paper's material ----
  lodestone_stage_params params;
  params.struct_size = sizeof params;
  check(a, a.api->stage_params_default(&params), "stage_params_default");
  params.law = LODESTONE_LAW_PAPER;
  for (int k = 0; k < 3; ++k) {
    params.grid.origin[k] = s.stageOrigin[k];
    params.grid.dims[k] = s.stageDims[k];
  }
  params.grid.dx = s.stageDx;
  params.padding = s.stagePadding;
  params.tolerance = s.tolerance;
  lodestone_stage* stage = nullptr;
  check(a, a.api->stage_create(a.ctx, &params, &stage), "stage_create");
  lodestone_fields* fields = nullptr;
  check(a, a.api->fields_create(a.ctx, &fields), "fields_create");
  const double axis[3] = {0, 0, 1};
  check(a,
        a.api->fields_add_cylinder_magnet(fields, s.magnetCenter, axis, s.magnetRadius, s.magnetHalfLength,
                                          s.magnetization),
        "fields_add_cylinder_magnet");

  // ---- particles: a lattice of spacing h inside the ball ----
  // n0 of the paper's material: 3.6e17 micro-particles per (7.8 mm)^3 cell.
  const double n0 = 3.6e17 / (7.8e-3 * 7.8e-3 * 7.8e-3);
  std::vector<Particle> particles;
  const double h = s.particleSpacing;
  const int nh = int(std::ceil(s.ballRadius / h)) + 1;
  for (int i = -nh; i < nh; ++i)
    for (int j = -nh; j < nh; ++j)
      for (int k = -nh; k < nh; ++k) {
        const double o[3] = {(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
        if (o[0] * o[0] + o[1] * o[1] + o[2] * o[2] > s.ballRadius * s.ballRadius) continue;
        Particle p{};
        for (int c = 0; c < 3; ++c) p.x[c] = s.ballCenter[c] + o[c];
        p.F[0] = p.F[4] = p.F[8] = 1.0;
        p.volume0 = h * h * h;
        p.mass = s.density * p.volume0;
        p.count = n0 * p.volume0;
        particles.push_back(p);
      }
  const std::size_t np = particles.size();

  lodestone_particles view;
  view.struct_size = sizeof view;
  view.type = LODESTONE_FLOAT64;
  view.count = np;
  view.positions = &particles[0].x[0];
  view.position_stride = sizeof(Particle);
  view.counts = &particles[0].count;
  view.count_stride = sizeof(Particle);

  std::vector<double> force(3 * np, 0.0);  // N, packed
  lodestone_vec3_out forceOut;
  forceOut.struct_size = sizeof forceOut;
  forceOut.type = LODESTONE_FLOAT64;
  forceOut.data = force.data();
  forceOut.stride = 0;
  forceOut.capacity = np;

  // ---- the host's MLS-MPM (mls-mpm88 style, Neo-Hookean) ----
  const double mu = s.youngsModulus / (2 * (1 + s.poissonRatio));
  const double lambda = s.youngsModulus * s.poissonRatio / ((1 + s.poissonRatio) * (1 - 2 * s.poissonRatio));
  const int gx = s.hostDims[0], gy = s.hostDims[1], gz = s.hostDims[2];
  const double dx = s.hostDx, inv = 1.0 / dx;
  std::vector<double> gm(std::size_t(gx) * gy * gz), gv(3 * gm.size());
  const auto node = [&](int i, int j, int k) {
    return std::size_t(i) + std::size_t(gx) * (std::size_t(j) + std::size_t(gy) * std::size_t(k));
  };

  const auto centreOfMass = [&](double c[3]) {
    double m = 0;
    c[0] = c[1] = c[2] = 0;
    for (const Particle& p : particles) {
      for (int d = 0; d < 3; ++d) c[d] += p.mass * p.x[d];
      m += p.mass;
    }
    for (int d = 0; d < 3; ++d) c[d] /= m;
  };

  std::vector<double> times, com, forces;
  double t = 0;
  int solves = 0, newtonTotal = 0;
  bool allConverged = true;
  double c[3];
  centreOfMass(c);
  times.push_back(t);
  com.insert(com.end(), c, c + 3);

  const int substeps = int(std::lround(1.0 / (s.fps * s.dt)));
  for (int frame = 0; frame < s.frames; ++frame) {
    // One field solve per frame at the particles' positions, then the
    // conservative per-particle forces, kept for the frame's substeps.
    lodestone_report report;
    report.struct_size = sizeof report;
    check(a, a.api->stage_run_particles(stage, &view, fields, t, &report), "stage_run_particles");
    check(a, a.api->stage_particle_forces(stage, &view, &forceOut), "stage_particle_forces");
    ++solves;
    newtonTotal += report.newton_iterations;
    allConverged = allConverged && report.converged;
    double total[3] = {0, 0, 0};
    for (std::size_t p = 0; p < np; ++p)
      for (int d = 0; d < 3; ++d) total[d] += force[3 * p + d];
    forces.insert(forces.end(), total, total + 3);

    for (int step = 0; step < substeps; ++step) {
      std::fill(gm.begin(), gm.end(), 0.0);
      std::fill(gv.begin(), gv.end(), 0.0);
      // P2G: APIC momentum, MLS stress impulse, magnetic impulse.
      for (std::size_t pi = 0; pi < np; ++pi) {
        const Particle& p = particles[pi];
        int base[3];
        double w[3][3], fx[3];
        for (int d = 0; d < 3; ++d) weights((p.x[d] - s.hostOrigin[d]) * inv, base[d], w[d], fx[d]);
        double Ft[9], FinvT[9], P[9], stress[9];
        invT(p.F, FinvT);
        const double J = det(p.F);
        for (int q = 0; q < 9; ++q) P[q] = mu * (p.F[q] - FinvT[q]) + lambda * std::log(J) * FinvT[q];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) Ft[3 * i + j] = p.F[3 * j + i];
        matMul(P, Ft, stress);
        double affine[9];
        for (int q = 0; q < 9; ++q) affine[q] = -s.dt * p.volume0 * 4 * inv * inv * stress[q] + p.mass * p.C[q];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) {
              const double weight = w[0][i] * w[1][j] * w[2][k];
              const double dpos[3] = {(i - fx[0]) * dx, (j - fx[1]) * dx, (k - fx[2]) * dx};
              const std::size_t n = node(base[0] + i, base[1] + j, base[2] + k);
              gm[n] += weight * p.mass;
              for (int d = 0; d < 3; ++d)
                gv[3 * n + d] += weight * (p.mass * p.v[d] + affine[3 * d] * dpos[0] + affine[3 * d + 1] * dpos[1] +
                                           affine[3 * d + 2] * dpos[2] + s.dt * force[3 * pi + d]);
            }
      }
      // Grid: velocities; the outer two node layers are sticky walls.
      for (int k = 0; k < gz; ++k)
        for (int j = 0; j < gy; ++j)
          for (int i = 0; i < gx; ++i) {
            const std::size_t n = node(i, j, k);
            if (gm[n] <= 0) continue;
            const bool wall = i < 2 || j < 2 || k < 2 || i >= gx - 2 || j >= gy - 2 || k >= gz - 2;
            for (int d = 0; d < 3; ++d) gv[3 * n + d] = wall ? 0.0 : gv[3 * n + d] / gm[n];
          }
      // G2P: APIC velocity and affine matrix, F update, advection.
      for (Particle& p : particles) {
        int base[3];
        double w[3][3], fx[3];
        for (int d = 0; d < 3; ++d) weights((p.x[d] - s.hostOrigin[d]) * inv, base[d], w[d], fx[d]);
        double v[3] = {0, 0, 0}, C[9] = {0};
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) {
              const double weight = w[0][i] * w[1][j] * w[2][k];
              const double dpos[3] = {(i - fx[0]) * dx, (j - fx[1]) * dx, (k - fx[2]) * dx};
              const std::size_t n = node(base[0] + i, base[1] + j, base[2] + k);
              for (int d = 0; d < 3; ++d) {
                v[d] += weight * gv[3 * n + d];
                for (int e = 0; e < 3; ++e) C[3 * d + e] += 4 * inv * inv * weight * gv[3 * n + d] * dpos[e];
              }
            }
        double G[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        for (int q = 0; q < 9; ++q) G[q] += s.dt * C[q];
        matMul(G, p.F, p.F);
        for (int d = 0; d < 3; ++d) {
          p.v[d] = v[d];
          p.x[d] += s.dt * v[d];
        }
        std::memcpy(p.C, C, sizeof C);
      }
      t += s.dt;
    }
    centreOfMass(c);
    times.push_back(t);
    com.insert(com.end(), c, c + 3);
    std::printf("frame %d  t = %.4f s  centre of mass z = %.6f m  magnetic force z = %.4f N  Newton %d\n", frame + 1, t,
                c[2], total[2], report.newton_iterations);
  }

  char reportJson[4096];
  std::size_t needed = 0;
  check(a, a.api->stage_report_json(stage, reportJson, sizeof reportJson, &needed), "stage_report_json");

  // ---- summary ----
  FILE* f = std::fopen(outPath.c_str(), "w");
  if (!f) die("cannot write " + outPath);
  const auto vec = [&](const double* v) { std::fprintf(f, "[%.17g, %.17g, %.17g]", v[0], v[1], v[2]); };
  std::fprintf(f, "{\n  \"setup\": {\n    \"ball_center_m\": ");
  vec(s.ballCenter);
  std::fprintf(f, ",\n    \"ball_radius_m\": %.17g,\n    \"particle_spacing_m\": %.17g,\n", s.ballRadius,
               s.particleSpacing);
  std::fprintf(f, "    \"density_kg_m3\": %.17g,\n    \"youngs_modulus_Pa\": %.17g,\n    \"poisson_ratio\": %.17g,\n",
               s.density, s.youngsModulus, s.poissonRatio);
  std::fprintf(f, "    \"magnet_center_m\": ");
  vec(s.magnetCenter);
  std::fprintf(
      f,
      ",\n    \"magnet_radius_m\": %.17g,\n    \"magnet_half_length_m\": %.17g,\n    \"magnetization_A_m\": %.17g,\n",
      s.magnetRadius, s.magnetHalfLength, s.magnetization);
  std::fprintf(f, "    \"stage_origin_m\": ");
  vec(s.stageOrigin);
  std::fprintf(f, ",\n    \"stage_dx_m\": %.17g,\n    \"stage_dims\": [%d, %d, %d],\n    \"stage_padding\": %d,\n",
               s.stageDx, s.stageDims[0], s.stageDims[1], s.stageDims[2], s.stagePadding);
  std::fprintf(f, "    \"tolerance\": %.17g,\n    \"host_origin_m\": ", s.tolerance);
  vec(s.hostOrigin);
  std::fprintf(f, ",\n    \"host_dx_m\": %.17g,\n    \"host_dims\": [%d, %d, %d],\n", s.hostDx, s.hostDims[0],
               s.hostDims[1], s.hostDims[2]);
  std::fprintf(f, "    \"dt_s\": %.17g,\n    \"fps\": %.17g,\n    \"frames\": %d\n  },\n", s.dt, s.fps, s.frames);
  std::fprintf(
      f, "  \"particles\": %zu,\n  \"field_solves\": %d,\n  \"newton_iterations\": %d,\n  \"all_converged\": %s,\n", np,
      solves, newtonTotal, allConverged ? "true" : "false");
  std::fprintf(f, "  \"times_s\": [");
  for (std::size_t k = 0; k < times.size(); ++k) std::fprintf(f, "%s%.17g", k ? ", " : "", times[k]);
  std::fprintf(f, "],\n  \"centre_of_mass_m\": [");
  for (std::size_t k = 0; k < times.size(); ++k) {
    std::fprintf(f, "%s", k ? ", " : "");
    vec(&com[3 * k]);
  }
  std::fprintf(f, "],\n  \"magnetic_force_N\": [");
  for (std::size_t k = 0; k + 2 < forces.size(); k += 3) {
    std::fprintf(f, "%s", k ? ", " : "");
    vec(&forces[k]);
  }
  std::fprintf(f, "],\n  \"last_report\": %s\n}\n", reportJson);
  std::fclose(f);

  check(a, a.api->fields_destroy(fields), "fields_destroy");
  check(a, a.api->stage_destroy(stage), "stage_destroy");
  check(a, a.api->context_destroy(a.ctx), "context_destroy");
  dlclose(a.lib);
  std::printf("wrote %s\n", outPath.c_str());
  return 0;
}
