// The node library: every node cooks with its defaults, validation names the
// node and the parameter, a throwing cook becomes a status, the generated
// docs are up to date, and a network built through the C ABI gives the
// stage's numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "lodestone/core/field/material.h"
#include "lodestone/plugin/errors.h"
#include "lodestone/plugin/lodestone.h"
#include "lodestone/plugin/network.h"
#include "lodestone/plugin/param_json.h"
#include "lodestone/plugin/node_registry.h"

using namespace lodestone;
using namespace lodestone::plugin;

namespace {

/// Adds a node of `type` named `name` and, recursively, a default provider
/// for each of its required inputs.
void addWithProviders(Network& net, const std::string& type, const std::string& name) {
  static const std::map<PortType, std::string> provider = {{PortType::Particles, "particle_source"},
                                                           {PortType::Material, "material"},
                                                           {PortType::Sources, "magnet"},
                                                           {PortType::Colliders, "collider"},
                                                           {PortType::Density, "magnetization_transfer"},
                                                           {PortType::Field, "field_solve"},
                                                           {PortType::Simulation, "mpm_solver"}};
  net.addNode(type, name);
  for (const PortDecl& in : requireNode(type).inputs) {
    if (in.optional) continue;
    const std::string up = name + "_" + in.name;
    addWithProviders(net, provider.at(in.type), up);
    net.connect(up, requireNode(provider.at(in.type)).outputs.front().name, name, in.name);
  }
}

TEST(PluginNodes, RegistryHasTheNodeLibrary) {
  const char* expected[] = {
      "particle_source", "material",       "magnet",     "applied_field", "magnetization_transfer",
      "field_solve",     "magnetic_force", "mpm_solver", "collider",      "vdb_export", "field_lines"};
  for (const char* t : expected) EXPECT_NE(findNode(t), nullptr) << t;
  for (const NodeDecl& d : nodeRegistry()) {
    EXPECT_FALSE(d.outputs.empty()) << d.type;
    for (const ParamDecl& p : d.params) {
      EXPECT_FALSE(p.help.empty()) << d.type << "." << p.name;
      EXPECT_NO_THROW(p.check(p.defaultValue, d.type)) << d.type << "." << p.name << " default out of range";
      if (!p.when.param.empty()) {
        EXPECT_NE(d.param(p.when.param), nullptr) << d.type << "." << p.name;
      }
    }
  }
}

TEST(PluginNodes, EveryNodeCooksWithItsDefaults) {
  for (const NodeDecl& d : nodeRegistry()) {
    Network net;
    addWithProviders(net, d.type, "node");
    const bool writesVdb = d.type == "vdb_export" || d.type == "surface" || d.type == "mesh_export";
    if (writesVdb) net.setParam("node", "path", ::testing::TempDir() + "defaults_" + d.type + ".vdb");
    if (d.type == "mesh_export") net.setParam("node", "path", ::testing::TempDir() + "defaults_mesh.ply");
    if (d.type == "field_lines") {
      // Traced through the default solve's field and sources.
      net.setParam("node", "path", ::testing::TempDir() + "defaults_lines.obj");
      net.addNode("magnet", "m");
      net.connect("m", "sources", "node_field", "sources");
      net.connect("m", "sources", "node", "sources");
    }
    if (writesVdb && !vdbBuilt()) {
      try {
        net.cook("node");
        ADD_FAILURE() << d.type << " cooked without OpenVDB";
      } catch (const CookFailed& e) {
        EXPECT_TRUE(e.notBuilt()) << e.what();
      }
      continue;
    }
    try {
      const CookOutputs& out = net.cook("node");
      for (const PortDecl& p : d.outputs) EXPECT_EQ(typeOf(out.at(p.name)), p.type) << d.type << "." << p.name;
      if (d.type == "field_lines") {
        std::ifstream in(::testing::TempDir() + "defaults_lines.obj");
        std::string line;
        int polylines = 0;
        while (std::getline(in, line)) polylines += line.rfind("l ", 0) == 0;
        EXPECT_GE(polylines, 10) << "field lines of the default magnet and material";
      }
    } catch (const std::exception& e) {
      ADD_FAILURE() << d.type << ": " << e.what();
    }
  }
}

std::string errorOf(const std::function<void()>& f);

TEST(PluginNodes, ParticleSourceFillsAMeshWhenVdbIsBuilt) {
  // A cube of side 4 cm as an OBJ mesh (outward, counter-clockwise faces).
  const std::string path = ::testing::TempDir() + "cube.obj";
  {
    std::ofstream obj(path);
    obj << "v -0.02 -0.02 -0.02\nv 0.02 -0.02 -0.02\nv 0.02 0.02 -0.02\nv -0.02 0.02 -0.02\n"
           "v -0.02 -0.02 0.02\nv 0.02 -0.02 0.02\nv 0.02 0.02 0.02\nv -0.02 0.02 0.02\n"
           "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  }
  Network net;
  net.addNode("particle_source", "cube");
  net.setParam("cube", "shape", std::string("mesh"));
  net.setParam("cube", "file", path);
  net.setParam("cube", "voxel_size", 0.004);
  net.setParam("cube", "cell_size", 0.008);
  if (!vdbBuilt()) {
    EXPECT_NE(errorOf([&] { net.cook("cube"); }).find("needs OpenVDB"), std::string::npos);
    return;
  }
  const auto p = std::get<std::shared_ptr<const ParticlesData>>(net.cook("cube").at("particles"));
  double volume = 0;
  for (double v : p->particles.volume0) volume += v;
  // The lattice of spacing 4 mm inside the level set: the cube's 64 cm^3 up
  // to the staircase error of one lattice layer (4 mm on 4 cm: < 30%).
  EXPECT_NEAR(volume, 6.4e-5, 0.3 * 6.4e-5);
  EXPECT_GT(p->particles.size(), 500u);
  const Vec3d c = p->particles.centreOfMass();
  EXPECT_LT(norm(c), 1e-3);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(PluginNodes, ValidationErrorsNameTheNodeAndTheParameter) {
  Network net;
  net.addNode("material", "ferro");
  net.addNode("particle_source", "blob");
  struct Case {
    std::function<void()> call;
    std::vector<std::string> expected;
  };
  const std::vector<Case> cases = {
      {[&] { net.setParam("ferro", "density", -5.0); }, {"node 'ferro' (material)", "density", "kg/m^3", "> 0", "-5"}},
      {[&] { net.setParam("ferro", "densty", 1.0); }, {"node 'ferro' (material)", "densty", "did you mean 'density'"}},
      {[&] { net.setParam("ferro", "model", std::string("gel")); },
       {"ferro", "model", "one of 'solid', 'fluid', 'viscoplastic_fluid' or 'elastoplastic_solid', found 'gel'"}},
      {[&] { net.setParam("ferro", "poisson_ratio", 0.6); }, {"ferro", "poisson_ratio", "in [0, 0.49]"}},
      {[&] { net.setParam("blob", "particles_per_cell", 2.5); },
       {"node 'blob' (particle_source)", "particles_per_cell", "integer"}},
      {[&] {
         net.setParam("blob", "half_size", Vec3d{0.1, -0.1, 0.1});
       },
       {"node 'blob' (particle_source): half_size[1]: expected a number in m > 0, found number -0.1"}},
      {[&] {
         net.setParam("blob", "axis", Vec3d{0, 0, 0});
       },
       {"blob", "axis", "non-zero"}},
      {[&] { net.setParam("blob", "center", 1.0); }, {"blob", "center", "an array of 3 numbers [x, y, z] in m"}},
      {[&] { net.addNode("magnett", "m"); }, {"unknown node type 'magnett'"}},
      {[&] { net.connect("ferro", "material", "blob", "materal"); }, {"blob", "materal", "did you mean 'material'"}},
      {[&] { net.connect("blob", "particles", "ferro", "x"); }, {"ferro", "no input named 'x'"}},
  };
  for (const Case& c : cases) {
    const std::string e = errorOf(c.call);
    for (const std::string& s : c.expected) EXPECT_NE(e.find(s), std::string::npos) << "'" << s << "' not in: " << e;
  }
  // Type mismatch and cycles.
  net.addNode("magnetization_transfer", "n");
  EXPECT_NE(errorOf([&] { net.connect("ferro", "material", "n", "particles"); }).find("takes particles"),
            std::string::npos);
  net.connect("ferro", "material", "blob", "material");
  EXPECT_NE(errorOf([&] { net.connect("ferro", "material", "blob", "material"); }).find("already has one"),
            std::string::npos);
}

TEST(PluginNodes, AThrowingCookIsReportedNotPropagated) {
  NodeDecl bad;
  bad.type = "throws";
  bad.outputs = {{"sources", PortType::Sources, "never"}};
  int which = 0;
  bad.cook = [&which](const CookContext&) -> CookOutputs {
    if (which == 0) throw std::runtime_error("boom inside the cook");
    if (which == 1) throw 42;  // not even a std::exception
    return {};                 // no outputs at all
  };
  for (which = 0; which < 3; ++which) {
    Network net;
    net.addNode(bad, "b");
    net.addNode("applied_field", "f");
    net.connect("b", "sources", "f", "sources");
    const std::string e = errorOf([&] { net.cook("f"); });
    EXPECT_NE(e.find("node 'b' (throws)"), std::string::npos) << e;
    if (which == 0) {
      EXPECT_NE(e.find("boom inside the cook"), std::string::npos) << e;
    }
  }
  // Through the C ABI: a cook throwing (mpm_solver with an empty domain) is a status and a message.
  const lodestone_api* a = nullptr;
  ASSERT_EQ(lodestone_get_api(1, 0, &a), LODESTONE_OK);
  lodestone_context* ctx = nullptr;
  ASSERT_EQ(a->context_create(&ctx), LODESTONE_OK);
  lodestone_network* n = nullptr;
  ASSERT_EQ(a->network_create(ctx, &n), LODESTONE_OK);
  ASSERT_EQ(a->network_add_node(n, "particle_source", "p"), LODESTONE_OK);
  ASSERT_EQ(a->network_add_node(n, "mpm_solver", "sim"), LODESTONE_OK);
  ASSERT_EQ(a->network_connect(n, "p", "particles", "sim", "particles"), LODESTONE_OK);
  const double lo[3] = {0.1, -0.1, -0.1};
  ASSERT_EQ(a->network_set_vec3(n, "sim", "domain.min", lo), LODESTONE_OK);
  EXPECT_EQ(a->network_cook(n, "sim"), LODESTONE_ERROR_COOK_FAILED);
  const std::string msg = a->context_last_error(ctx);
  EXPECT_NE(msg.find("node 'sim' (mpm_solver)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("max must exceed min"), std::string::npos) << msg;
  size_t needed = 0;
  EXPECT_EQ(a->network_output_json(n, "sim", "simulation", nullptr, 0, &needed), LODESTONE_ERROR_NOT_READY);
  EXPECT_EQ(a->network_destroy(n), LODESTONE_OK);
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_OK);
}

TEST(PluginNodes, DocsNodesMdIsUpToDate) {
  std::ifstream in(LODESTONE_DOCS_DIR "/nodes.md");
  ASSERT_TRUE(in) << "cannot read docs/nodes.md";
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_TRUE(ss.str() == nodesMarkdown()) << "docs/nodes.md differs from the node declarations; regenerate it with "
                                              "`lodestone nodes --markdown > docs/nodes.md`";
}

// A shape's help names only shapes its node offers, and the help of
// `center` says that scene files read it for the file shapes too.
TEST(PluginNodes, ShapeHelpNamesOnlyTheOfferedShapes) {
  const std::vector<std::string> allShapes = {"plane", "box", "sphere", "cylinder", "level_set", "mesh"};
  for (const NodeDecl& d : nodeRegistry()) {
    const ParamDecl* shape = d.param("shape");
    if (!shape) continue;
    for (const std::string& s : allShapes) {
      const bool offered = std::find(shape->choices.begin(), shape->choices.end(), s) != shape->choices.end();
      if (!offered) {
        EXPECT_EQ(shape->help.find(s), std::string::npos) << d.type << ": " << shape->help;
      }
    }
    const ParamDecl* center = d.param("center");
    const bool fileShapes = std::find(shape->choices.begin(), shape->choices.end(), "mesh") != shape->choices.end();
    if (center && fileShapes) {
      EXPECT_NE(center->help.find("level_set and mesh"), std::string::npos) << d.type << ": " << center->help;
    }
  }
}

std::string outputJson(const lodestone_api* a, lodestone_network* n, const char* node, const char* out) {
  size_t needed = 0;
  EXPECT_EQ(a->network_output_json(n, node, out, nullptr, 0, &needed), LODESTONE_OK);
  std::string s(needed, '\0');
  EXPECT_EQ(a->network_output_json(n, node, out, s.data(), s.size(), &needed), LODESTONE_OK);
  s.resize(needed - 1);
  return s;
}

TEST(PluginNodes, ANetworkBuiltThroughTheCAbiGivesConservativeForces) {
  const lodestone_api* a = nullptr;
  ASSERT_EQ(lodestone_get_api(1, 0, &a), LODESTONE_OK);
  // Metadata: every node's parameters are listed with their defaults.
  ASSERT_EQ(a->node_type_count(), nodeRegistry().size());
  for (uint32_t k = 0; k < a->node_type_count(); ++k) {
    lodestone_node_info info{};
    info.struct_size = sizeof info;
    ASSERT_EQ(a->node_type_info(k, &info), LODESTONE_OK);
    for (uint32_t q = 0; q < info.param_count; ++q) {
      lodestone_param_info p{};
      p.struct_size = sizeof p;
      ASSERT_EQ(a->node_param_info(info.type, q, &p), LODESTONE_OK);
      EXPECT_GT(std::strlen(p.default_text), 0u) << info.type << "." << p.name;
    }
    lodestone_param_info p{};
    p.struct_size = sizeof p;
    EXPECT_EQ(a->node_param_info(info.type, info.param_count, &p), LODESTONE_ERROR_NOT_FOUND);
  }

  lodestone_context* ctx = nullptr;
  ASSERT_EQ(a->context_create(&ctx), LODESTONE_OK);
  lodestone_network* n = nullptr;
  ASSERT_EQ(a->network_create(ctx, &n), LODESTONE_OK);
  const auto ok = [&](lodestone_status s) { EXPECT_EQ(s, LODESTONE_OK) << a->context_last_error(ctx); };
  ok(a->network_add_node(n, "material", "ferro"));
  ok(a->network_set_json(n, "ferro", R"({"name": "ferro", "density": 1200, "magnetic": {"law": "paper"}})"));
  ok(a->network_add_node(n, "particle_source", "ball"));
  ok(a->network_set_string(n, "ball", "shape", "sphere"));
  ok(a->network_set_float(n, "ball", "radius", 0.015));
  const double centre[3] = {0, 0, 0.02};
  ok(a->network_set_vec3(n, "ball", "center", centre));
  ok(a->network_set_float(n, "ball", "cell_size", 0.006));
  ok(a->network_connect(n, "ferro", "material", "ball", "material"));
  ok(a->network_add_node(n, "magnet", "magnet"));
  ok(a->network_set_json(n, "magnet", R"({"shape": "cylinder", "center": [0, 0, -0.03], "radius": 0.02,
                                          "half_length": 0.01, "magnetization": 8e5})"));
  ok(a->network_add_node(n, "magnetization_transfer", "n"));
  ok(a->network_set_float(n, "n", "dx", 0.005));
  ok(a->network_connect(n, "ball", "particles", "n", "particles"));
  ok(a->network_add_node(n, "field_solve", "solve"));
  ok(a->network_connect(n, "n", "density", "solve", "density"));
  ok(a->network_connect(n, "magnet", "sources", "solve", "sources"));
  ok(a->network_add_node(n, "magnetic_force", "force"));
  ok(a->network_connect(n, "solve", "field", "force", "field"));
  ok(a->network_connect(n, "ball", "particles", "force", "particles"));
  // Wrong values through the ABI: statuses naming node and parameter.
  EXPECT_EQ(a->network_set_float(n, "ball", "radius", -1), LODESTONE_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(a->context_last_error(ctx)).find("node 'ball' (particle_source): radius"), std::string::npos)
      << a->context_last_error(ctx);
  EXPECT_EQ(a->network_set_float(n, "ball", "radius_m", 1), LODESTONE_ERROR_NOT_FOUND);
  // JSON is read as scene files are: the same messages, unknown keys with a
  // suggestion, duplicate keys and syntax errors located.
  const auto jsonError = [&](const char* node, const char* json) {
    EXPECT_EQ(a->network_set_json(n, node, json), LODESTONE_ERROR_INVALID_ARGUMENT) << json;
    return std::string(a->context_last_error(ctx));
  };
  EXPECT_NE(jsonError("ball", R"({"radius": -1})")
                .find("node 'ball' (particle_source): radius: expected a number in m > 0, found number -1"),
            std::string::npos);
  EXPECT_NE(jsonError("ferro", R"({"magnetic": {"lw": "paper"}})")
                .find("node 'ferro' (material): magnetic: unknown key 'lw'; did you mean 'law'?"),
            std::string::npos);
  EXPECT_NE(jsonError("ferro", R"({"densty": 1000})").find("unknown key 'densty'; did you mean 'density'?"),
            std::string::npos);
  EXPECT_NE(jsonError("ferro", R"({"density": 1000, "density": 2000})").find("duplicate key 'density'"),
            std::string::npos);
  EXPECT_NE(jsonError("ferro", "{\"density\": 1000,\n \"model\" \"solid\"}").find("node 'ferro' (material):2:"),
            std::string::npos);
  EXPECT_NE(jsonError("ferro", R"({"magnetic": {"law": "langevn"}})").find("did you mean 'langevin'?"),
            std::string::npos);
  EXPECT_NE(jsonError("ferro", R"({"density": 1200, "viscosity": "thick"})").find("viscosity: expected a number"),
            std::string::npos);
  EXPECT_EQ(a->network_add_node(n, "nonsense", "x"), LODESTONE_ERROR_NOT_FOUND);
  // Ports that do not exist are NOT_FOUND, as the header says, with a suggestion.
  EXPECT_EQ(a->network_connect(n, "ball", "particle", "n", "particles"), LODESTONE_ERROR_NOT_FOUND);
  EXPECT_NE(std::string(a->context_last_error(ctx)).find("did you mean 'particles'?"), std::string::npos)
      << a->context_last_error(ctx);
  EXPECT_EQ(a->network_connect(n, "ball", "particles", "n", "particle"), LODESTONE_ERROR_NOT_FOUND);
  EXPECT_EQ(a->network_connect(n, "ferro", "material", "force", "particles"), LODESTONE_ERROR_INVALID_ARGUMENT);

  ok(a->network_cook(n, "force"));
  const nlohmann::json field = nlohmann::json::parse(outputJson(a, n, "solve", "field"));
  const nlohmann::json force = nlohmann::json::parse(outputJson(a, n, "force", "forces"));
  const nlohmann::json ball = nlohmann::json::parse(outputJson(a, n, "ball", "particles"));
  EXPECT_TRUE(field["report"]["converged"].get<bool>()) << field.dump();
  const double fz = force["total_force_N"][2].get<double>(), nz = field["report"]["total_force_N"][2].get<double>();
  EXPECT_LT(fz, 0);                           // pulled toward the magnet below
  EXPECT_NEAR(fz, nz, 1e-9 * std::fabs(nz));  // sum over particles = sum over nodes
  EXPECT_EQ(force["particles"], ball["particles"]);
  // Ball mass: 1200 kg/m^3 times the emitted volume, within the staircase error of a sphere.
  const double volume = 4.0 / 3.0 * M_PI * std::pow(0.015, 3);
  EXPECT_NEAR(ball["mass_kg"].get<double>(), 1200 * volume, 0.1 * 1200 * volume);

  // Positions through a strided float output.
  const std::size_t count = ball["particles"].get<std::size_t>();
  std::vector<float> pos(4 * count);
  lodestone_vec3_out out{sizeof(lodestone_vec3_out), LODESTONE_FLOAT32, pos.data(), 4 * sizeof(float), count};
  size_t got = 0;
  ok(a->network_read_positions(n, "ball", "particles", &out, &got));
  EXPECT_EQ(got, count);
  double meanZ = 0;
  for (std::size_t k = 0; k < count; ++k) meanZ += pos[4 * k + 2] / double(count);
  EXPECT_NEAR(meanZ, 0.02, 1e-3);
  EXPECT_EQ(a->network_read_positions(n, "solve", "field", &out, &got), LODESTONE_ERROR_INVALID_ARGUMENT);

  // A change upstream re-cooks: a stronger magnet, a larger pull.
  ok(a->network_set_float(n, "magnet", "magnetization", 1.6e6));
  ok(a->network_cook(n, "force"));
  const nlohmann::json stronger = nlohmann::json::parse(outputJson(a, n, "force", "forces"));
  EXPECT_LT(stronger["total_force_N"][2].get<double>(), 1.5 * fz);
  ok(a->network_destroy(n));
  ok(a->context_destroy(ctx));
}

// Of two alternative parameters the one set last is used: magnetization set
// after remanence is not ignored, and the other way round.
TEST(PluginNodes, TheAlternativeSetLastIsUsed) {
  const auto magnetizationOf = [](const std::vector<std::pair<std::string, double>>& sets) {
    Network net;
    net.addNode("magnet", "m");
    for (const auto& [name, value] : sets) net.setParam("m", name, value);
    const auto& sources = std::get<std::shared_ptr<const SourcesData>>(net.cook("m").at("sources"));
    return sources->magnets.at(0).magnet->magnetization({0, 0, -0.05}, 0).z;  // the centre
  };
  const double fromBr = 1.0 / (4e-7 * M_PI);
  EXPECT_NEAR(magnetizationOf({{"remanence", 1.0}}), fromBr, 1e-6 * fromBr);
  EXPECT_DOUBLE_EQ(magnetizationOf({{"remanence", 1.0}, {"magnetization", 5e5}}), 5e5);
  EXPECT_NEAR(magnetizationOf({{"magnetization", 5e5}, {"remanence", 1.0}}), fromBr, 1e-6 * fromBr);
  // Number density after per_cell, for a material.
  const auto n0Of = [](const std::vector<std::pair<std::string, double>>& sets) {
    Network net;
    net.addNode("material", "m");
    net.setParam("m", "magnetic.law", std::string("linear"));
    for (const auto& [name, value] : sets) net.setParam("m", name, value);
    const auto& mat = std::get<std::shared_ptr<const MaterialData>>(net.cook("m").at("material"));
    return mat->material.magnetic.numberDensity;
  };
  EXPECT_DOUBLE_EQ(n0Of({{"magnetic.per_cell", 1e3}, {"magnetic.cell_size", 0.1}}), 1e6);
  EXPECT_DOUBLE_EQ(n0Of({{"magnetic.per_cell", 1e3}, {"magnetic.cell_size", 0.1}, {"magnetic.number_density", 5e5}}),
                   5e5);
}

// A host builds a whole network from JSON, feeds its own particles in and
// reads the per-particle forces out: the forces of the same points emitted by
// a particle_source node, bit for bit.
TEST(PluginNodes, AHostNetworkFromJsonTakesTheHostsParticlesAndGivesTheirForces) {
  const char* magnet = R"({"shape": "cylinder", "center": [0, 0, -0.03], "radius": 0.02, "half_length": 0.01,
                           "magnetization": 8e5})";
  // The reference: points emitted by a particle_source.
  Network ref;
  ref.addNode("material", "ferro");
  setParamsFromJson(ref, "ferro", nlohmann::json::parse(R"({"magnetic": {"law": "paper"}})"), "ferro");
  ref.addNode("particle_source", "ball");
  setParamsFromJson(ref, "ball",
                    nlohmann::json::parse(R"({"shape": "sphere", "radius": 0.015, "center": [0, 0, 0.02],
                                              "cell_size": 0.006})"),
                    "ball");
  ref.connect("ferro", "material", "ball", "material");
  ref.addNode("magnet", "magnet");
  setParamsFromJson(ref, "magnet", nlohmann::json::parse(magnet), "magnet");
  ref.addNode("magnetization_transfer", "n");
  ref.addNode("field_solve", "solve");
  ref.addNode("magnetic_force", "force");
  ref.connect("ball", "particles", "n", "particles");
  ref.connect("n", "density", "solve", "density");
  ref.connect("magnet", "sources", "solve", "sources");
  ref.connect("solve", "field", "force", "field");
  ref.connect("ball", "particles", "force", "particles");
  const auto& refForces = std::get<std::shared_ptr<const ForcesData>>(ref.cook("force").at("forces"))->particleForces;
  const MpmParticles& pts = std::get<std::shared_ptr<const ParticlesData>>(ref.cook("ball").at("particles"))->particles;
  ASSERT_GT(pts.size(), 100u);

  const lodestone_api* a = nullptr;
  ASSERT_EQ(lodestone_get_api(1, 1, &a), LODESTONE_OK);
  lodestone_context* ctx = nullptr;
  ASSERT_EQ(a->context_create(&ctx), LODESTONE_OK);
  const std::string json = std::string(R"({"nodes": [
      {"name": "ferro", "type": "material", "params": {"magnetic": {"law": "paper"}}},
      {"name": "host", "type": "host_particles"},
      {"name": "magnet", "type": "magnet", "params": )") + magnet + R"(},
      {"name": "n", "type": "magnetization_transfer"},
      {"name": "solve", "type": "field_solve"},
      {"name": "force", "type": "magnetic_force"}],
    "connections": [
      {"from": "ferro", "output": "material", "to": "host", "input": "material"},
      {"from": "host", "output": "particles", "to": "n", "input": "particles"},
      {"from": "n", "output": "density", "to": "solve", "input": "density"},
      {"from": "magnet", "output": "sources", "to": "solve", "input": "sources"},
      {"from": "solve", "output": "field", "to": "force", "input": "field"},
      {"from": "host", "output": "particles", "to": "force", "input": "particles"}]})";
  lodestone_network* n = nullptr;
  ASSERT_EQ(a->network_create_from_json(ctx, json.c_str(), &n), LODESTONE_OK) << a->context_last_error(ctx);
  lodestone_particles view{};
  view.struct_size = sizeof view;
  view.type = LODESTONE_FLOAT64;
  view.count = pts.size();
  view.positions = pts.x.data();
  view.counts = pts.count.data();
  ASSERT_EQ(a->network_set_particles(n, "host", &view), LODESTONE_OK) << a->context_last_error(ctx);
  ASSERT_EQ(a->network_cook(n, "force"), LODESTONE_OK) << a->context_last_error(ctx);
  std::vector<double> forces(3 * pts.size());
  lodestone_vec3_out out{sizeof(lodestone_vec3_out), LODESTONE_FLOAT64, forces.data(), 0, pts.size()};
  size_t count = 0;
  ASSERT_EQ(a->network_read_forces(n, "force", "forces", &out, &count), LODESTONE_OK) << a->context_last_error(ctx);
  EXPECT_EQ(count, pts.size());
  for (std::size_t k = 0; k < pts.size(); ++k)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(forces[3 * k + d], refForces[k][d]) << k;
  EXPECT_EQ(a->network_read_forces(n, "host", "particles", &out, &count), LODESTONE_ERROR_INVALID_ARGUMENT);
  // A node that takes no particles.
  EXPECT_EQ(a->network_set_particles(n, "solve", &view), LODESTONE_ERROR_NOT_FOUND);
  EXPECT_EQ(a->network_destroy(n), LODESTONE_OK);

  // Errors name the path; no network is made.
  const auto refused = [&](const std::string& text, const std::string& expected) {
    lodestone_network* m = reinterpret_cast<lodestone_network*>(&view);
    EXPECT_EQ(a->network_create_from_json(ctx, text.c_str(), &m), LODESTONE_ERROR_INVALID_ARGUMENT) << text;
    EXPECT_EQ(m, nullptr);
    EXPECT_NE(std::string(a->context_last_error(ctx)).find(expected), std::string::npos) << a->context_last_error(ctx);
  };
  refused(R"({"nodes": [{"name": "a", "type": "materal"}]})", "nodes[0].type");
  refused(R"({"nodes": [{"name": "a", "type": "material", "params": {"densty": 1}}]})", "did you mean 'density'?");
  refused(R"({"nodes": [{"name": "a", "type": "material"}], "conections": []})", "did you mean 'connections'?");
  refused(R"({"nodes": [{"name": "a", "type": "material"}, {"name": "b", "type": "particle_source"}],
              "connections": [{"from": "a", "output": "material", "to": "b", "input": "materal"}]})",
          "connections[0]: node 'b' (particle_source): no input named 'materal'; did you mean 'material'?");
  refused("{\"nodes\": [}", "network:1:");

  // The stage's n0, for the host's counts.
  lodestone_stage_params params{};
  params.struct_size = sizeof params;
  ASSERT_EQ(a->stage_params_default(&params), LODESTONE_OK);
  params.grid.dims[0] = params.grid.dims[1] = params.grid.dims[2] = 4;
  const std::pair<int32_t, double> laws[] = {{LODESTONE_LAW_PAPER, paperMaterial().numberDensity},
                                             {LODESTONE_LAW_LINEAR, 2.5e20},
                                             {LODESTONE_LAW_NONE, 0.0}};
  for (const auto& [law, n0] : laws) {
    params.law = law;
    params.number_density = law == LODESTONE_LAW_LINEAR ? 2.5e20 : 0.0;
    lodestone_stage* stage = nullptr;
    ASSERT_EQ(a->stage_create(ctx, &params, &stage), LODESTONE_OK) << a->context_last_error(ctx);
    double got = -1;
    EXPECT_EQ(a->stage_number_density(stage, &got), LODESTONE_OK);
    EXPECT_EQ(got, n0) << law;
    EXPECT_EQ(a->stage_destroy(stage), LODESTONE_OK);
  }
  EXPECT_EQ(a->context_destroy(ctx), LODESTONE_OK);
}

}  // namespace
