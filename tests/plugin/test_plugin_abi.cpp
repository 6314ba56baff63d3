// The C ABI: version negotiation, null handles, sizes and strides, results
// equal to the core stage's, concurrent stages, networks of nodes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "lodestone/core/sources/cylinder_magnet.h"
#include "lodestone/core/stage/magnetic_stage.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/field/solve_settings.h"
#include "lodestone/plugin/lodestone.h"

namespace {

const lodestone_api* api() {
  const lodestone_api* t = nullptr;
  EXPECT_EQ(lodestone_get_api(LODESTONE_API_VERSION_MAJOR, LODESTONE_API_VERSION_MINOR, &t), LODESTONE_OK);
  return t;
}

std::string lastError() { return api()->thread_last_error(); }

/// A ball of particles (lattice spacing h) with the paper's n0.
struct Ball {
  std::vector<double> x, n;
  std::size_t size() const { return n.size(); }
  Ball(lodestone::Vec3d c, double r, double h) {
    const double n0 = lodestone::paperMaterial().numberDensity;
    const int m = int(std::ceil(r / h)) + 1;
    for (int i = -m; i < m; ++i)
      for (int j = -m; j < m; ++j)
        for (int k = -m; k < m; ++k) {
          const lodestone::Vec3d o{(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
          if (lodestone::norm(o) > r) continue;
          for (int a = 0; a < 3; ++a) x.push_back(c[a] + o[a]);
          n.push_back(n0 * h * h * h);
        }
  }
  lodestone_particles view() const {
    lodestone_particles p{};
    p.struct_size = sizeof p;
    p.type = LODESTONE_FLOAT64;
    p.count = size();
    p.positions = x.data();
    p.counts = n.data();
    return p;
  }
};

struct Fixture {
  const lodestone_api* a = api();
  lodestone_context* ctx = nullptr;
  lodestone_stage* stage = nullptr;
  lodestone_fields* fields = nullptr;
  lodestone_stage_params params{};
  Fixture() {
    EXPECT_EQ(a->context_create(&ctx), LODESTONE_OK);
    params.struct_size = sizeof params;
    EXPECT_EQ(a->stage_params_default(&params), LODESTONE_OK);
    params.grid = {{-0.04, -0.04, -0.02}, 0.005, {17, 17, 17}};
    EXPECT_EQ(a->stage_create(ctx, &params, &stage), LODESTONE_OK) << lastError();
    EXPECT_EQ(a->fields_create(ctx, &fields), LODESTONE_OK);
    const double c[3] = {0, 0, -0.035}, axis[3] = {0, 0, 1};
    EXPECT_EQ(a->fields_add_cylinder_magnet(fields, c, axis, 0.02, 0.01, 8e5), LODESTONE_OK);
  }
  ~Fixture() {
    EXPECT_EQ(a->fields_destroy(fields), LODESTONE_OK);
    EXPECT_EQ(a->stage_destroy(stage), LODESTONE_OK);
    EXPECT_EQ(a->context_destroy(ctx), LODESTONE_OK) << lastError();
  }
};

TEST(PluginAbi, VersionNegotiationFollowsTheDocumentedRule) {
  const lodestone_api* t = nullptr;
  ASSERT_EQ(lodestone_get_api(1, 0, &t), LODESTONE_OK);
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->major, 1u);
  EXPECT_EQ(t->minor, std::uint32_t(LODESTONE_API_VERSION_MINOR));  // the library's own minor, not the one asked for
  EXPECT_EQ(t->struct_size, sizeof(lodestone_api));
  // A newer minor than the library's, another major: refused with a message.
  const std::pair<uint32_t, uint32_t> refused[] = {{1, LODESTONE_API_VERSION_MINOR + 1}, {2, 0}, {0, 0}, {0, 9}};
  for (const auto& [major, minor] : refused) {
    const lodestone_api* r = reinterpret_cast<const lodestone_api*>(&t);  // non-null: must be reset
    EXPECT_EQ(lodestone_get_api(major, minor, &r), LODESTONE_ERROR_VERSION) << major << "." << minor;
    EXPECT_EQ(r, nullptr);
    const std::string msg = t->thread_last_error();
    EXPECT_NE(msg.find(std::to_string(major) + "." + std::to_string(minor) + " requested"), std::string::npos) << msg;
    EXPECT_NE(msg.find("provides 1."), std::string::npos) << msg;
  }
  EXPECT_EQ(lodestone_get_api(1, 0, nullptr), LODESTONE_ERROR_NULL_HANDLE);
  EXPECT_STREQ(t->status_string(LODESTONE_ERROR_VERSION), "unsupported API version");
}

TEST(PluginAbi, EveryFunctionRejectsNullHandles) {
  const lodestone_api* a = api();
  Fixture f;
  const double v[3] = {0, 0, 1};
  lodestone_particles p{};
  p.struct_size = sizeof p;
  lodestone_vec3_out out{};
  out.struct_size = sizeof out;
  lodestone_report rep{};
  rep.struct_size = sizeof rep;
  lodestone_grid g{};
  double buf[4];
  size_t needed = 0;
  uint32_t count = 0;
  lodestone_param_info pi{};
  pi.struct_size = sizeof pi;
  lodestone_port_info po{};
  po.struct_size = sizeof po;
  struct Case {
    const char* name;
    std::function<lodestone_status()> call;
  };
  const std::vector<Case> cases = {
      {"context_create", [&] { return a->context_create(nullptr); }},
      {"fields_create ctx",
       [&] {
         lodestone_fields* x;
         return a->fields_create(nullptr, &x);
       }},
      {"fields_create out", [&] { return a->fields_create(f.ctx, nullptr); }},
      {"fields_add_uniform", [&] { return a->fields_add_uniform(nullptr, v); }},
      {"fields_add_uniform H", [&] { return a->fields_add_uniform(f.fields, nullptr); }},
      {"fields_add_dipole", [&] { return a->fields_add_dipole(nullptr, v, v); }},
      {"fields_add_sphere_magnet", [&] { return a->fields_add_sphere_magnet(nullptr, v, v, 0.01, 1e5); }},
      {"fields_add_box_magnet", [&] { return a->fields_add_box_magnet(nullptr, v, v, v, 1e5); }},
      {"fields_add_box_magnet size", [&] { return a->fields_add_box_magnet(f.fields, v, v, nullptr, 1e5); }},
      {"fields_add_cylinder_magnet", [&] { return a->fields_add_cylinder_magnet(nullptr, v, v, 0.01, 0.01, 1e5); }},
      {"fields_add_vdb", [&] { return a->fields_add_vdb(nullptr, "x.vdb", "H"); }},
      {"fields_add_vdb path", [&] { return a->fields_add_vdb(f.fields, nullptr, "H"); }},
      {"fields_count", [&] { return a->fields_count(nullptr, &count); }},
      {"fields_count out", [&] { return a->fields_count(f.fields, nullptr); }},
      {"fields_evaluate", [&] { return a->fields_evaluate(nullptr, v, 0, buf); }},
      {"stage_params_default", [&] { return a->stage_params_default(nullptr); }},
      {"stage_create ctx",
       [&] {
         lodestone_stage* s;
         return a->stage_create(nullptr, &f.params, &s);
       }},
      {"stage_create params",
       [&] {
         lodestone_stage* s;
         return a->stage_create(f.ctx, nullptr, &s);
       }},
      {"stage_create out", [&] { return a->stage_create(f.ctx, &f.params, nullptr); }},
      {"stage_grid", [&] { return a->stage_grid(nullptr, &g); }},
      {"stage_grid out", [&] { return a->stage_grid(f.stage, nullptr); }},
      {"stage_run_particles", [&] { return a->stage_run_particles(nullptr, &p, f.fields, 0, &rep); }},
      {"stage_run_particles particles", [&] { return a->stage_run_particles(f.stage, nullptr, f.fields, 0, &rep); }},
      {"stage_run_density", [&] { return a->stage_run_density(nullptr, &g, buf, f.fields, 0, &rep); }},
      {"stage_run_density grid", [&] { return a->stage_run_density(f.stage, nullptr, buf, f.fields, 0, &rep); }},
      {"stage_run_density data", [&] { return a->stage_run_density(f.stage, &g, nullptr, f.fields, 0, &rep); }},
      {"stage_particle_forces", [&] { return a->stage_particle_forces(nullptr, &p, &out); }},
      {"stage_sample", [&] { return a->stage_sample(nullptr, LODESTONE_FIELD_H, &p, &out); }},
      {"stage_read_field", [&] { return a->stage_read_field(nullptr, LODESTONE_FIELD_H, LODESTONE_FLOAT64, buf, 4); }},
      {"stage_report", [&] { return a->stage_report(nullptr, &rep); }},
      {"stage_report_json", [&] { return a->stage_report_json(nullptr, nullptr, 0, &needed); }},
      {"stage_export_vdb", [&] { return a->stage_export_vdb(nullptr, "x.vdb"); }},
      {"node_type_info", [&] { return a->node_type_info(0, nullptr); }},
      {"node_param_info type", [&] { return a->node_param_info(nullptr, 0, &pi); }},
      {"node_param_info out", [&] { return a->node_param_info("material", 0, nullptr); }},
      {"node_input_info", [&] { return a->node_input_info(nullptr, 0, &po); }},
      {"node_output_info", [&] { return a->node_output_info(nullptr, 0, &po); }},
      {"network_create",
       [&] {
         lodestone_network* n;
         return a->network_create(nullptr, &n);
       }},
      {"network_add_node", [&] { return a->network_add_node(nullptr, "material", "m"); }},
      {"network_set_float", [&] { return a->network_set_float(nullptr, "m", "density", 1.0); }},
      {"network_set_int", [&] { return a->network_set_int(nullptr, "m", "x", 1); }},
      {"network_set_bool", [&] { return a->network_set_bool(nullptr, "m", "x", 1); }},
      {"network_set_string", [&] { return a->network_set_string(nullptr, "m", "x", "y"); }},
      {"network_set_vec3", [&] { return a->network_set_vec3(nullptr, "m", "x", v); }},
      {"network_set_json", [&] { return a->network_set_json(nullptr, "m", "{}"); }},
      {"network_connect", [&] { return a->network_connect(nullptr, "a", "b", "c", "d"); }},
      {"network_cook", [&] { return a->network_cook(nullptr, "m"); }},
      {"network_output_json", [&] { return a->network_output_json(nullptr, "m", "o", nullptr, 0, &needed); }},
      {"network_read_positions", [&] { return a->network_read_positions(nullptr, "m", "o", &out, &needed); }},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(c.call(), LODESTONE_ERROR_NULL_HANDLE) << c.name;
    EXPECT_NE(lastError().find("NULL"), std::string::npos) << c.name << ": " << lastError();
  }
  // Destroying NULL is a no-op.
  EXPECT_EQ(a->stage_destroy(nullptr), LODESTONE_OK);
  EXPECT_EQ(a->fields_destroy(nullptr), LODESTONE_OK);
  EXPECT_EQ(a->network_destroy(nullptr), LODESTONE_OK);
  EXPECT_EQ(a->context_destroy(nullptr), LODESTONE_OK);
}

TEST(PluginAbi, BadSizesStridesAndValuesGiveAStatus) {
  Fixture f;
  const lodestone_api* a = f.a;
  const Ball ball({0, 0, 0.012}, 0.012, 0.004);
  std::vector<double> forces(3 * ball.size());
  lodestone_vec3_out out{};
  out.struct_size = sizeof out;
  out.type = LODESTONE_FLOAT64;
  out.data = forces.data();
  out.capacity = ball.size();

  // Reading before any run.
  EXPECT_EQ(a->stage_particle_forces(f.stage, nullptr, &out), LODESTONE_ERROR_NOT_READY);
  std::vector<double> field(3 * 17 * 17 * 17);
  EXPECT_EQ(a->stage_read_field(f.stage, LODESTONE_FIELD_H, LODESTONE_FLOAT64, field.data(), field.size()),
            LODESTONE_ERROR_NOT_READY);
  EXPECT_NE(std::string(a->context_last_error(f.ctx)).find("has not run"), std::string::npos);

  struct Case {
    const char* name;
    std::function<void(lodestone_particles&)> spoil;
    lodestone_status expected;
  };
  const std::vector<Case> particleCases = {
      {"struct_size 0", [](lodestone_particles& p) { p.struct_size = 0; }, LODESTONE_ERROR_INVALID_ARGUMENT},
      {"struct_size short", [](lodestone_particles& p) { p.struct_size = 8; }, LODESTONE_ERROR_INVALID_ARGUMENT},
      {"scalar type", [](lodestone_particles& p) { p.type = 7; }, LODESTONE_ERROR_INVALID_ARGUMENT},
      {"position stride", [](lodestone_particles& p) { p.position_stride = 16; }, LODESTONE_ERROR_INVALID_ARGUMENT},
      {"count stride", [](lodestone_particles& p) { p.count_stride = 4; }, LODESTONE_ERROR_INVALID_ARGUMENT},
      {"positions NULL", [](lodestone_particles& p) { p.positions = nullptr; }, LODESTONE_ERROR_NULL_HANDLE},
      {"counts NULL", [](lodestone_particles& p) { p.counts = nullptr; }, LODESTONE_ERROR_NULL_HANDLE},
      {"huge count", [](lodestone_particles& p) { p.count = std::size_t(1) << 50; }, LODESTONE_ERROR_INVALID_ARGUMENT},
  };
  for (const Case& c : particleCases) {
    lodestone_particles p = ball.view();
    c.spoil(p);
    EXPECT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, nullptr), c.expected) << c.name;
    EXPECT_FALSE(std::string(a->context_last_error(f.ctx)).empty()) << c.name;
  }
  // Particles outside the grid (OUT_OF_GRID_THROW) and non-finite time.
  {
    Ball far = ball;
    far.x[0] = 5.0;
    const lodestone_particles p = far.view();
    EXPECT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, nullptr), LODESTONE_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(a->context_last_error(f.ctx)).find("particle"), std::string::npos)
        << a->context_last_error(f.ctx);
    const lodestone_particles q = ball.view();
    EXPECT_EQ(a->stage_run_particles(f.stage, &q, f.fields, NAN, nullptr), LODESTONE_ERROR_INVALID_ARGUMENT);
  }
  lodestone_report rep{};
  rep.struct_size = 4;
  const lodestone_particles p = ball.view();
  EXPECT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, &rep), LODESTONE_ERROR_INVALID_ARGUMENT);
  rep.struct_size = sizeof rep;
  ASSERT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, &rep), LODESTONE_OK) << a->context_last_error(f.ctx);

  // Output arrays.
  const std::vector<std::pair<const char*, std::function<void(lodestone_vec3_out&)>>> outCases = {
      {"struct_size", [](lodestone_vec3_out& o) { o.struct_size = 1; }},
      {"type", [](lodestone_vec3_out& o) { o.type = -1; }},
      {"stride", [](lodestone_vec3_out& o) { o.stride = 8; }},
  };
  for (const auto& [name, spoil] : outCases) {
    lodestone_vec3_out o = out;
    spoil(o);
    EXPECT_EQ(a->stage_particle_forces(f.stage, &p, &o), LODESTONE_ERROR_INVALID_ARGUMENT) << name;
  }
  lodestone_vec3_out small = out;
  small.capacity = ball.size() - 1;
  EXPECT_EQ(a->stage_particle_forces(f.stage, &p, &small), LODESTONE_ERROR_BUFFER_TOO_SMALL);
  EXPECT_EQ(a->stage_read_field(f.stage, LODESTONE_FIELD_H, LODESTONE_FLOAT64, field.data(), field.size() - 1),
            LODESTONE_ERROR_BUFFER_TOO_SMALL);
  EXPECT_EQ(a->stage_read_field(f.stage, 99, LODESTONE_FLOAT64, field.data(), field.size()),
            LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(a->stage_read_field(f.stage, LODESTONE_FIELD_H, 5, field.data(), field.size()),
            LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(a->stage_sample(f.stage, LODESTONE_FIELD_M, &p, &out), LODESTONE_ERROR_INVALID_ARGUMENT);
  char tiny[4];
  size_t needed = 0;
  EXPECT_EQ(a->stage_report_json(f.stage, tiny, sizeof tiny, &needed), LODESTONE_ERROR_BUFFER_TOO_SMALL);
  EXPECT_GT(needed, sizeof tiny);
  std::string json(needed, '\0');
  EXPECT_EQ(a->stage_report_json(f.stage, json.data(), json.size(), &needed), LODESTONE_OK);
  EXPECT_NE(json.find("\"converged\":true"), std::string::npos) << json;
  // The same fields object again: H_ext at the nodes is kept. After a field
  // is added it is evaluated again.
  const auto reused = [&] {
    EXPECT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, nullptr), LODESTONE_OK) << a->context_last_error(f.ctx);
    std::string j(4096, '\0');
    size_t n = 0;
    EXPECT_EQ(a->stage_report_json(f.stage, j.data(), j.size(), &n), LODESTONE_OK);
    return j.find("\"applied_field_reused\":true") != std::string::npos;
  };
  EXPECT_TRUE(reused());
  const double H[3] = {0, 0, 1e3};
  ASSERT_EQ(a->fields_add_uniform(f.fields, H), LODESTONE_OK);
  EXPECT_FALSE(reused());
  EXPECT_TRUE(reused());

  // Stage parameters.
  const std::vector<std::pair<const char*, std::function<void(lodestone_stage_params&)>>> paramCases = {
      {"struct_size", [](lodestone_stage_params& q) { q.struct_size = 12; }},
      {"law", [](lodestone_stage_params& q) { q.law = 17; }},
      {"dx", [](lodestone_stage_params& q) { q.grid.dx = -1; }},
      {"dims", [](lodestone_stage_params& q) { q.grid.dims[1] = 1; }},
      {"padding", [](lodestone_stage_params& q) { q.padding = 65; }},
      {"tolerance", [](lodestone_stage_params& q) { q.tolerance = 2; }},
      {"boundary", [](lodestone_stage_params& q) { q.boundary = 3; }},
      {"out_of_grid", [](lodestone_stage_params& q) { q.out_of_grid = 3; }},
      {"newton", [](lodestone_stage_params& q) { q.max_newton_iterations = 0; }},
      {"moment",
       [](lodestone_stage_params& q) {
         q.law = LODESTONE_LAW_LANGEVIN;
         q.moment = -1;
       }},
      {"chi",
       [](lodestone_stage_params& q) {
         q.law = LODESTONE_LAW_LINEAR;
         q.chi = NAN;
       }},
      // Out of range though the law does not use it.
      {"chi for Langevin",
       [](lodestone_stage_params& q) {
         q.law = LODESTONE_LAW_LANGEVIN;
         q.chi = -0.5;
       }},
      {"temperature for linear",
       [](lodestone_stage_params& q) {
         q.law = LODESTONE_LAW_LINEAR;
         q.temperature = -1;
       }},
      {"number_density", [](lodestone_stage_params& q) { q.number_density = -1; }},
  };
  for (const auto& [name, spoil] : paramCases) {
    lodestone_stage_params q = f.params;
    spoil(q);
    lodestone_stage* s = reinterpret_cast<lodestone_stage*>(&q);
    EXPECT_EQ(a->stage_create(f.ctx, &q, &s), LODESTONE_ERROR_INVALID_ARGUMENT) << name;
    EXPECT_EQ(s, nullptr) << name;
  }
  // Grids that pass validation but cannot fit: refused before allocating,
  // naming the padded size (in 64 bits) and the memory it needs.
  const auto tooLarge = [&](int nx, int nyz, int pad) {
    lodestone_stage_params q = f.params;
    q.grid.dims[0] = nx;
    q.grid.dims[1] = q.grid.dims[2] = nyz;
    q.padding = pad;
    lodestone_stage* s = nullptr;
    EXPECT_EQ(a->stage_create(f.ctx, &q, &s), LODESTONE_ERROR_OUT_OF_MEMORY) << nx;
    EXPECT_EQ(s, nullptr);
    return std::string(a->context_last_error(f.ctx));
  };
  std::string msg = tooLarge(3000, 3000, 0);  // 2.7e10 nodes, about 15 TiB
  EXPECT_NE(msg.find("a grid of 3000 x 3000 x 3000 nodes"), std::string::npos) << msg;
  EXPECT_NE(msg.find("GiB"), std::string::npos) << msg;
  msg = tooLarge(2147483647, 10, 4);  // 2.1e11 nodes pass the grid's validation; padded, the count is past INT32_MAX
  EXPECT_NE(msg.find("a grid of 2147483655 x 18 x 18 nodes"), std::string::npos) << msg;
  // Particles the estimate refuses (2^39 points, 200 TiB), before their arrays are read.
  {
    lodestone_particles many = ball.view();
    many.count = std::size_t(1) << 39;
    EXPECT_EQ(a->stage_run_particles(f.stage, &many, f.fields, 0, nullptr), LODESTONE_ERROR_OUT_OF_MEMORY);
    EXPECT_NE(std::string(a->context_last_error(f.ctx)).find("549755813888 particles are too many"), std::string::npos)
        << a->context_last_error(f.ctx);
  }
  // A time that is not a number.
  {
    const double x[3] = {0, 0, 0};
    double Hout[3];
    EXPECT_EQ(a->fields_evaluate(f.fields, x, NAN, Hout), LODESTONE_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(a->context_last_error(f.ctx)).find("time must be finite"), std::string::npos);
  }
  // Density on another grid than the stage's.
  lodestone_grid other = {{0, 0, 0}, 0.01, {3, 3, 3}};
  std::vector<double> n(27, 0.0);
  EXPECT_EQ(a->stage_run_density(f.stage, &other, n.data(), f.fields, 0, nullptr), LODESTONE_ERROR_INVALID_ARGUMENT);
  // Magnet values.
  const double c[3] = {0, 0, 0}, zero[3] = {0, 0, 0}, z[3] = {0, 0, 1};
  EXPECT_EQ(a->fields_add_sphere_magnet(f.fields, c, zero, 0.01, 1e5), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(a->fields_add_sphere_magnet(f.fields, c, z, -0.01, 1e5), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(a->fields_add_sphere_magnet(f.fields, c, z, 0.01, 1e9), LODESTONE_ERROR_INVALID_ARGUMENT);
  // The context refuses to go while it owns objects.
  EXPECT_EQ(a->context_destroy(f.ctx), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(lastError()).find("still owns 2"), std::string::npos) << lastError();
}

TEST(PluginAbi, StageMatchesTheCoreStageAndAcceptsFloatsAndStrides) {
  Fixture f;
  const lodestone_api* a = f.a;
  const Ball ball({0.003, -0.002, 0.012}, 0.012, 0.004);
  const lodestone_particles p = ball.view();
  lodestone_report rep{};
  rep.struct_size = sizeof rep;
  ASSERT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, &rep), LODESTONE_OK) << a->context_last_error(f.ctx);
  EXPECT_TRUE(rep.converged);
  std::vector<double> forces(3 * ball.size());
  lodestone_vec3_out out{sizeof(lodestone_vec3_out), LODESTONE_FLOAT64, forces.data(), 0, ball.size()};
  ASSERT_EQ(a->stage_particle_forces(f.stage, &p, &out), LODESTONE_OK);

  // The same through the core directly: identical numbers.
  lodestone::GridSpec g{{-0.04, -0.04, -0.02}, 0.005, {17, 17, 17}};
  lodestone::MagneticStageSettings s;
  s.solve.tolerance = f.params.tolerance;
  lodestone::MagneticForceStage core(g, lodestone::paperMaterial(), s);
  lodestone::CylinderMagnet magnet(lodestone::Pose::at({0, 0, -0.035}), 0.02, 0.01, {0, 0, 8e5});
  std::vector<lodestone::Vec3d> x(ball.size()), fc(ball.size());
  for (std::size_t k = 0; k < ball.size(); ++k) x[k] = {ball.x[3 * k], ball.x[3 * k + 1], ball.x[3 * k + 2]};
  const auto coreRep = core.run({x.data(), ball.n.data(), ball.size()}, magnet, 0);
  core.particleForces({x.data(), ball.n.data(), ball.size()}, fc.data());
  EXPECT_EQ(rep.newton_iterations, coreRep.solve.newtonIterations);
  double sum[3] = {0, 0, 0};
  for (std::size_t k = 0; k < ball.size(); ++k)
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(forces[3 * k + d], fc[k][d]) << k;
      sum[d] += forces[3 * k + d];
    }
  // Conservative forces: the particles' sum is the nodal total, and the ball is pulled down.
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(sum[d], rep.total_force[d], 1e-9 * std::fabs(rep.total_force[2])) << d;
  EXPECT_LT(rep.total_force[2], 0);

  // Float32 input in an array of structs (stride 20 bytes) and float32 output
  // with a stride: the same forces to float precision.
  struct Host {
    float x[3], n;
    float pad;
  };
  std::vector<Host> host(ball.size());
  for (std::size_t k = 0; k < ball.size(); ++k) {
    for (int d = 0; d < 3; ++d) host[k].x[d] = float(ball.x[3 * k + d]);
    host[k].n = float(ball.n[k]);
  }
  lodestone_particles pf{
      sizeof(lodestone_particles), LODESTONE_FLOAT32, ball.size(), host[0].x, sizeof(Host), &host[0].n, sizeof(Host)};
  ASSERT_EQ(a->stage_run_particles(f.stage, &pf, f.fields, 0, nullptr), LODESTONE_OK);
  std::vector<float> ff(4 * ball.size(), -1.0f);
  lodestone_vec3_out outf{sizeof(lodestone_vec3_out), LODESTONE_FLOAT32, ff.data(), 4 * sizeof(float), ball.size()};
  ASSERT_EQ(a->stage_particle_forces(f.stage, &pf, &outf), LODESTONE_OK);
  const double scale = std::fabs(rep.total_force[2]) / double(ball.size());
  for (std::size_t k = 0; k < ball.size(); ++k) {
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(ff[4 * k + d], forces[3 * k + d], 1e-3 * scale + 1e-5 * std::fabs(forces[3 * k + d]));
    EXPECT_EQ(ff[4 * k + 3], -1.0f);  // the stride's gap is untouched
  }

  // Fields: H read back equals the core's; B = mu0 (H + M) at a node.
  lodestone_grid grid;
  ASSERT_EQ(a->stage_grid(f.stage, &grid), LODESTONE_OK);
  const std::size_t nodes = std::size_t(grid.dims[0]) * grid.dims[1] * grid.dims[2];
  std::vector<double> H(3 * nodes), M(3 * nodes), B(3 * nodes);
  ASSERT_EQ(a->stage_run_particles(f.stage, &p, f.fields, 0, nullptr), LODESTONE_OK);
  ASSERT_EQ(a->stage_read_field(f.stage, LODESTONE_FIELD_H, LODESTONE_FLOAT64, H.data(), H.size()), LODESTONE_OK);
  ASSERT_EQ(a->stage_read_field(f.stage, LODESTONE_FIELD_M, LODESTONE_FLOAT64, M.data(), M.size()), LODESTONE_OK);
  ASSERT_EQ(a->stage_read_field(f.stage, LODESTONE_FIELD_B, LODESTONE_FLOAT64, B.data(), B.size()), LODESTONE_OK);
  const std::size_t mid = std::size_t(8) + 17 * (8 + 17 * 6);
  for (int d = 0; d < 3; ++d) {
    // Within the solve's tolerance: the stage has run three times (warm starts), the core once.
    EXPECT_NEAR(H[3 * mid + d], core.field()[mid][d], 1e-6 * std::fabs(H[3 * mid + 2]));
    EXPECT_NEAR(B[3 * mid + d], 4e-7 * M_PI * (H[3 * mid + d] + M[3 * mid + d]),
                1e-6 * std::fabs(B[3 * mid + 2]) + 1e-12);
  }
  EXPECT_GT(M[3 * mid + 2], 0);
  // Export: written with OpenVDB, a clear refusal without.
  const std::string path = ::testing::TempDir() + "plugin_fields.vdb";
  const lodestone_status e = a->stage_export_vdb(f.stage, path.c_str());
  if (a->has_vdb()) {
    EXPECT_EQ(e, LODESTONE_OK) << a->context_last_error(f.ctx);
    // Read back as an applied field: H at a node is the exported H (float grid).
    lodestone_fields* fromFile = nullptr;
    ASSERT_EQ(a->fields_create(f.ctx, &fromFile), LODESTONE_OK);
    ASSERT_EQ(a->fields_add_vdb(fromFile, path.c_str(), "H"), LODESTONE_OK) << a->context_last_error(f.ctx);
    const double at[3] = {grid.origin[0] + 8 * grid.dx, grid.origin[1] + 8 * grid.dx, grid.origin[2] + 6 * grid.dx};
    double h[3];
    ASSERT_EQ(a->fields_evaluate(fromFile, at, 0, h), LODESTONE_OK);
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(h[d], H[3 * mid + d], 1e-6 * std::fabs(H[3 * mid + 2]) + 1e-3) << d;
    EXPECT_EQ(a->fields_add_vdb(fromFile, path.c_str(), "no_such_grid"), LODESTONE_ERROR_IO);
    EXPECT_EQ(a->fields_add_vdb(fromFile, "/nonexistent/x.vdb", "H"), LODESTONE_ERROR_IO);
    EXPECT_EQ(a->fields_destroy(fromFile), LODESTONE_OK);
  } else {
    EXPECT_EQ(e, LODESTONE_ERROR_NOT_BUILT);
    EXPECT_NE(std::string(a->context_last_error(f.ctx)).find("not built"), std::string::npos);
  }

  // The forces are those of the last run's particles: another set (fewer, or
  // moved) is refused with a message instead of forces that sum to something else.
  lodestone_particles fewer = p;
  fewer.count = p.count - 10;
  EXPECT_EQ(a->stage_particle_forces(f.stage, &fewer, &out), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(lastError().find("the last run() deposited"), std::string::npos) << lastError();
  Ball moved = ball;
  for (std::size_t i = 2; i < moved.x.size(); i += 3) moved.x[i] += 0.005;
  const lodestone_particles pm = moved.view();
  EXPECT_EQ(a->stage_particle_forces(f.stage, &pm, &out), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(lastError().find("not the last run()"), std::string::npos) << lastError();
}

TEST(PluginAbi, TwoStagesOnTwoThreadsMatchASerialRun) {
  const lodestone_api* a = api();
  lodestone_context* ctx = nullptr;
  ASSERT_EQ(a->context_create(&ctx), LODESTONE_OK);
  lodestone_fields* fields = nullptr;
  ASSERT_EQ(a->fields_create(ctx, &fields), LODESTONE_OK);
  const double c[3] = {0, 0, -0.035}, axis[3] = {0, 0, 1};
  ASSERT_EQ(a->fields_add_cylinder_magnet(fields, c, axis, 0.02, 0.01, 8e5), LODESTONE_OK);
  const Ball balls[2] = {Ball({0, 0, 0.012}, 0.012, 0.004), Ball({0.004, 0, 0.015}, 0.01, 0.0035)};
  const auto runOne = [&](int which, std::vector<double>& forces, std::string& error) {
    lodestone_stage_params params{};
    params.struct_size = sizeof params;
    a->stage_params_default(&params);
    params.grid = {{-0.04, -0.04, -0.02}, 0.005, {17, 17, 17}};
    lodestone_stage* stage = nullptr;
    if (a->stage_create(ctx, &params, &stage) != LODESTONE_OK) {
      error = a->context_last_error(ctx);
      return;
    }
    const lodestone_particles p = balls[which].view();
    forces.assign(3 * balls[which].size(), 0.0);
    lodestone_vec3_out out{sizeof(lodestone_vec3_out), LODESTONE_FLOAT64, forces.data(), 0, balls[which].size()};
    for (int step = 0; step < 3; ++step)  // warm starts too
      if (a->stage_run_particles(stage, &p, fields, 0.001 * step, nullptr) != LODESTONE_OK ||
          a->stage_particle_forces(stage, &p, &out) != LODESTONE_OK)
        error = a->context_last_error(ctx);
    a->stage_destroy(stage);
  };
  std::vector<double> serial[2], parallel[2];
  std::string errors[4];
  runOne(0, serial[0], errors[0]);
  runOne(1, serial[1], errors[1]);
  std::thread t0([&] { runOne(0, parallel[0], errors[2]); });
  std::thread t1([&] { runOne(1, parallel[1], errors[3]); });
  t0.join();
  t1.join();
  for (const std::string& e : errors) EXPECT_EQ(e, "");
  EXPECT_EQ(serial[0], parallel[0]);
  EXPECT_EQ(serial[1], parallel[1]);
  EXPECT_NE(serial[0], std::vector<double>(serial[0].size(), 0.0));
  EXPECT_EQ(a->fields_destroy(fields), LODESTONE_OK);
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_OK);
}

TEST(PluginAbi, LastErrorIsPerThreadAndPerContext) {
  const lodestone_api* a = api();
  lodestone_context* ctx = nullptr;
  ASSERT_EQ(a->context_create(&ctx), LODESTONE_OK);
  lodestone_fields* fields = nullptr;
  ASSERT_EQ(a->fields_create(ctx, &fields), LODESTONE_OK);
  const double bad[3] = {NAN, 0, 0};
  EXPECT_EQ(a->fields_add_uniform(fields, bad), LODESTONE_ERROR_INVALID_ARGUMENT);
  const std::string mine = a->context_last_error(ctx);
  EXPECT_NE(mine.find("fields_add_uniform"), std::string::npos) << mine;
  std::string other = "unset";
  std::thread([&] { other = a->context_last_error(ctx); }).join();
  EXPECT_EQ(other, "");
  EXPECT_EQ(a->fields_destroy(fields), LODESTONE_OK);
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_OK);
}

// A handle used after its destroy (destroyed twice, say), one of another
// kind and a value never handed out give LODESTONE_ERROR_INVALID_HANDLE, also
// after many objects were created and destroyed meanwhile (slots reused).
TEST(PluginAbi, StaleAndForeignHandlesGiveAStatus) {
  const lodestone_api* a = api();
  lodestone_context* ctx = nullptr;
  ASSERT_EQ(a->context_create(&ctx), LODESTONE_OK);
  lodestone_stage_params params{};
  params.struct_size = sizeof params;
  ASSERT_EQ(a->stage_params_default(&params), LODESTONE_OK);
  params.grid.dims[0] = params.grid.dims[1] = params.grid.dims[2] = 5;
  lodestone_stage* stage = nullptr;
  lodestone_fields* fields = nullptr;
  lodestone_network* network = nullptr;
  ASSERT_EQ(a->stage_create(ctx, &params, &stage), LODESTONE_OK) << lastError();
  ASSERT_EQ(a->fields_create(ctx, &fields), LODESTONE_OK);
  ASSERT_EQ(a->network_create(ctx, &network), LODESTONE_OK);
  // Of another kind, or never handed out.
  lodestone_grid g{};
  uint32_t count = 0;
  EXPECT_EQ(a->stage_grid(reinterpret_cast<lodestone_stage*>(fields), &g), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_NE(lastError().find("not a live handle"), std::string::npos) << lastError();
  EXPECT_EQ(a->fields_count(reinterpret_cast<lodestone_fields*>(stage), &count), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(a->network_cook(reinterpret_cast<lodestone_network*>(ctx), "x"), LODESTONE_ERROR_INVALID_HANDLE);
  double junk[8] = {};
  EXPECT_EQ(a->stage_destroy(reinterpret_cast<lodestone_stage*>(junk)), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(a->context_destroy(reinterpret_cast<lodestone_context*>(junk)), LODESTONE_ERROR_INVALID_HANDLE);

  EXPECT_EQ(a->stage_destroy(stage), LODESTONE_OK);
  EXPECT_EQ(a->fields_destroy(fields), LODESTONE_OK);
  EXPECT_EQ(a->network_destroy(network), LODESTONE_OK);
  // Many objects later (their slots reused), the old handles are still stale.
  for (int k = 0; k < 3000; ++k) {
    lodestone_fields* f = nullptr;
    ASSERT_EQ(a->fields_create(ctx, &f), LODESTONE_OK);
    ASSERT_NE(f, fields);
    ASSERT_EQ(a->fields_destroy(f), LODESTONE_OK);
  }
  lodestone_fields* fresh = nullptr;
  ASSERT_EQ(a->fields_create(ctx, &fresh), LODESTONE_OK);
  EXPECT_EQ(a->stage_destroy(stage), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_NE(lastError().find("stage_destroy: stage"), std::string::npos) << lastError();
  EXPECT_EQ(a->fields_destroy(fields), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(a->network_destroy(network), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(a->stage_grid(stage, &g), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(a->fields_count(fields, &count), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(a->network_add_node(network, "material", "m"), LODESTONE_ERROR_INVALID_HANDLE);
  // The live one still works; the context counts it.
  EXPECT_EQ(a->fields_count(fresh, &count), LODESTONE_OK);
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(a->fields_destroy(fresh), LODESTONE_OK);
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_OK);
  // A context destroyed twice, and objects asked of it.
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_NE(lastError().find("context_destroy: context"), std::string::npos) << lastError();
  EXPECT_EQ(a->fields_create(ctx, &fresh), LODESTONE_ERROR_INVALID_HANDLE);
  EXPECT_EQ(fresh, nullptr);
  EXPECT_STREQ(a->context_last_error(ctx), "");
  EXPECT_STREQ(a->status_string(LODESTONE_ERROR_INVALID_HANDLE), "invalid handle");
}

// One set of defaults: the stage parameters' and the solve nodes' tolerance
// and Newton cap are the core's FieldSolveSettings.
TEST(PluginAbi, DefaultsAreTheCoresSolveSettings) {
  const lodestone_api* a = api();
  const lodestone::FieldSolveSettings core;
  lodestone_stage_params params{};
  params.struct_size = sizeof params;
  ASSERT_EQ(a->stage_params_default(&params), LODESTONE_OK);
  EXPECT_EQ(params.tolerance, core.tolerance);
  EXPECT_EQ(params.max_newton_iterations, core.maxNewtonIterations);
  for (const char* type : {"field_solve", "mpm_solver"}) {
    lodestone_node_info info{};
    info.struct_size = sizeof info;
    int found = 0;
    for (uint32_t k = 0; k < a->node_type_count(); ++k) {
      ASSERT_EQ(a->node_type_info(k, &info), LODESTONE_OK);
      if (std::string(info.type) != type) continue;
      for (uint32_t q = 0; q < info.param_count; ++q) {
        lodestone_param_info p{};
        p.struct_size = sizeof p;
        ASSERT_EQ(a->node_param_info(type, q, &p), LODESTONE_OK);
        const std::string name = p.name;
        if (name == "tolerance" || name == "magnetic.tolerance") {
          EXPECT_EQ(std::stod(p.default_text), core.tolerance) << type;
          ++found;
        }
        if (name == "max_newton_iterations" || name == "magnetic.max_newton_iterations") {
          EXPECT_EQ(std::stoi(p.default_text), core.maxNewtonIterations) << type;
          ++found;
        }
      }
    }
    EXPECT_EQ(found, 2) << type;
  }
}

}  // namespace
