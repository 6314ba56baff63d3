// The C ABI's network entries: building, setting, cooking and reading node networks.
#include "support.h"

#include <nlohmann/json.hpp>

#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/network_json.h"
#include "lodestone/plugin/node_builders.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/param_json.h"

namespace lodestone::plugin::abi {

lodestone_status networkCreate(lodestone_context* c, lodestone_network** out) {
  return createEntry<lodestone_network, NetworkObject>(c, out, HandleKind::Network, "network_create");
}

lodestone_status networkDestroy(lodestone_network* n) {
  return firewall(ctxOf(n), "network_destroy", [&] { destroy<NetworkObject>(n, HandleKind::Network, "network"); });
}

Network& net(lodestone_network* n) { return networkOf(n).network; }

void checkNode(Network& network, const std::string& node) {
  if (!network.hasNode(node)) throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("no node named '", node, "'"));
}

void setParam(lodestone_network* n, const char* node, const char* param, const ParamValue& v) {
  Network& network = net(n);
  const std::string name = needName(node, "node"), key = needName(param, "param");
  checkNode(network, name);
  if (!network.declOf(name).param(key))
    throw AbiError(LODESTONE_ERROR_NOT_FOUND,
                   concat("node '", name, "' (", network.declOf(name).type, ") has no parameter '", key, "'"));
  network.setParam(name, key, v);
}

lodestone_status networkAddNode(lodestone_network* n, const char* type, const char* name) {
  return firewall(ctxOf(n), "network_add_node", [&] {
    Network& network = net(n);
    const std::string t = needName(type, "type"), nm = needName(name, "name");
    if (!findNode(t)) throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("no node type named '", t, "'"));
    network.addNode(t, nm);
  });
}

lodestone_status networkSetFloat(lodestone_network* n, const char* node, const char* param, double v) {
  return firewall(ctxOf(n), "network_set_float", [&] { setParam(n, node, param, v); });
}
lodestone_status networkSetInt(lodestone_network* n, const char* node, const char* param, int64_t v) {
  return firewall(ctxOf(n), "network_set_int", [&] { setParam(n, node, param, std::int64_t(v)); });
}
lodestone_status networkSetBool(lodestone_network* n, const char* node, const char* param, int32_t v) {
  return firewall(ctxOf(n), "network_set_bool", [&] { setParam(n, node, param, v != 0); });
}
lodestone_status networkSetString(lodestone_network* n, const char* node, const char* param, const char* v) {
  return firewall(ctxOf(n), "network_set_string", [&] { setParam(n, node, param, needName(v, "value")); });
}
lodestone_status networkSetVec3(lodestone_network* n, const char* node, const char* param, const double v[3]) {
  return firewall(ctxOf(n), "network_set_vec3", [&] {
    need(v, "value");
    setParam(n, node, param, Vec3d{v[0], v[1], v[2]});
  });
}

lodestone_status networkSetJson(lodestone_network* n, const char* node, const char* json) {
  return firewall(ctxOf(n), "network_set_json", [&] {
    Network& network = net(n);
    const std::string name = needName(node, "node"), text = needName(json, "json");
    checkNode(network, name);
    // The scene files' strict reading: syntax errors at line:column,
    // duplicate keys, unknown keys with a suggestion, types and ranges.
    const std::string where = concat("node '", name, "' (", network.declOf(name).type, ")");
    setParamsFromJson(network, name, parseJsonText(text, where), where);
  });
}

lodestone_status networkConnect(lodestone_network* n, const char* from, const char* output, const char* to,
                                const char* input) {
  return firewall(ctxOf(n), "network_connect", [&] {
    Network& network = net(n);
    const std::string f = needName(from, "from_node"), o = needName(output, "output"), t = needName(to, "to_node"),
                      i = needName(input, "input");
    checkNode(network, f);
    checkNode(network, t);
    if (!network.declOf(f).output(o) || !network.declOf(t).input(i)) {
      try {
        network.connect(f, o, t, i);  // throws, naming the port and the closest declared one
      } catch (const InvalidArgument& e) {
        throw AbiError(LODESTONE_ERROR_NOT_FOUND, e.what());
      }
    }
    network.connect(f, o, t, i);
  });
}

lodestone_status networkCook(lodestone_network* n, const char* node) {
  return firewall(ctxOf(n), "network_cook", [&] {
    Network& network = net(n);
    const std::string name = needName(node, "node");
    checkNode(network, name);
    network.cook(name);
  });
}

nlohmann::json vecJson(const Vec3d& v) { return {v.x, v.y, v.z}; }

nlohmann::json outputJson(const NodeValue& v) {
  nlohmann::json j;
  j["type"] = toString(typeOf(v));
  if (const auto* p = std::get_if<std::shared_ptr<const ParticlesData>>(&v)) {
    const MpmParticles& q = (*p)->particles;
    double count = 0;
    for (double c : q.count) count += c;
    j["particles"] = q.size();
    j["mass_kg"] = q.totalMass();
    j["micro_particles"] = count;
    j["centre_of_mass_m"] = vecJson(q.centreOfMass());
  } else if (const auto* m = std::get_if<std::shared_ptr<const MaterialData>>(&v)) {
    j["name"] = (*m)->name;
    j["describe"] = (*m)->material.describe();
  } else if (const auto* s = std::get_if<std::shared_ptr<const SourcesData>>(&v)) {
    j["fields"] = (*s)->fields.size();
    j["magnets"] = (*s)->magnets.size();
  } else if (const auto* c = std::get_if<std::shared_ptr<const CollidersData>>(&v)) {
    j["colliders"] = (*c)->colliders.size();
  } else if (const auto* d = std::get_if<std::shared_ptr<const DensityData>>(&v)) {
    const GridSpec& g = (*d)->density.spec();
    j["grid"] = {{"origin_m", vecJson(g.origin)}, {"dx_m", g.dx}, {"dims", {g.dims.i, g.dims.j, g.dims.k}}};
    j["total_count"] = (*d)->totalCount;
  } else if (const auto* f = std::get_if<std::shared_ptr<const FieldData>>(&v)) {
    j["report"] = nlohmann::json::parse(reportJson((*f)->report));
  } else if (const auto* fo = std::get_if<std::shared_ptr<const ForcesData>>(&v)) {
    j["particles"] = (*fo)->particleForces.size();
    j["total_force_N"] = vecJson((*fo)->total);
  } else if (const auto* sim = std::get_if<std::shared_ptr<const SimulationData>>(&v)) {
    j["start_frame"] = (*sim)->startFrame;
    j["frames"] = (*sim)->frames;
    j["time_s"] = (*sim)->time;
    j["particles"] = (*sim)->solver->particles().size();
    nlohmann::json com = nlohmann::json::array();
    for (const Vec3d& x : (*sim)->centreOfMass) com.push_back(vecJson(x));
    j["magnetic_centre_of_mass_m"] = com;
    j["frame_times_s"] = (*sim)->frameTimes;
  }
  return j;
}

const NodeValue& cookedOutput(lodestone_network* n, const char* node, const char* output) {
  Network& network = net(n);
  const std::string name = needName(node, "node"), out = needName(output, "output");
  checkNode(network, name);
  if (!network.declOf(name).output(out))
    throw AbiError(LODESTONE_ERROR_NOT_FOUND, concat("node '", name, "' has no output '", out, "'"));
  try {
    return network.output(name, out);
  } catch (const InvalidArgument& e) {
    throw AbiError(LODESTONE_ERROR_NOT_READY, e.what());
  }
}

lodestone_status networkOutputJson(lodestone_network* n, const char* node, const char* output, char* buffer,
                                   size_t capacity, size_t* needed) {
  return firewall(ctxOf(n), "network_output_json",
                  [&] { copyText(outputJson(cookedOutput(n, node, output)).dump(), buffer, capacity, needed); });
}

lodestone_status networkReadPositions(lodestone_network* n, const char* node, const char* output,
                                      lodestone_vec3_out* out, size_t* count) {
  return firewall(ctxOf(n), "network_read_positions", [&] {
    const NodeValue& v = cookedOutput(n, node, output);
    need(count, "count");
    const std::vector<Vec3d>* x = nullptr;
    if (const auto* p = std::get_if<std::shared_ptr<const ParticlesData>>(&v)) x = &(*p)->particles.x;
    if (const auto* s = std::get_if<std::shared_ptr<const SimulationData>>(&v)) x = &(*s)->solver->particles().x;
    if (!x)
      throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                     concat("output '", output, "' carries ", toString(typeOf(v)), ", not particles or a simulation"));
    *count = x->size();
    writeVectors(*x, out);
  });
}

lodestone_status networkSetParticles(lodestone_network* n, const char* node, const lodestone_particles* p) {
  return firewall(ctxOf(n), "network_set_particles", [&] {
    Network& network = net(n);
    const std::string name = needName(node, "node");
    checkNode(network, name);
    const Particles particles = readParticles(p, true);
    std::vector<double> x(3 * particles.x.size());
    for (std::size_t k = 0; k < particles.x.size(); ++k)
      for (int a = 0; a < 3; ++a) x[3 * k + std::size_t(a)] = particles.x[k][a];
    setParam(n, node, "positions", x);
    setParam(n, node, "counts", particles.n);
  });
}

lodestone_status networkReadForces(lodestone_network* n, const char* node, const char* output, lodestone_vec3_out* out,
                                   size_t* count) {
  return firewall(ctxOf(n), "network_read_forces", [&] {
    const NodeValue& v = cookedOutput(n, node, output);
    need(count, "count");
    const auto* f = std::get_if<std::shared_ptr<const ForcesData>>(&v);
    if (!f)
      throw AbiError(LODESTONE_ERROR_INVALID_ARGUMENT,
                     concat("output '", output, "' carries ", toString(typeOf(v)), ", not forces"));
    *count = (*f)->particleForces.size();
    writeVectors((*f)->particleForces, out);
  });
}

lodestone_status networkCreateFromJson(lodestone_context* c, const char* json, lodestone_network** out) {
  return firewall(ctxOf(c), "network_create_from_json", [&] {
    if (out) *out = nullptr;
    Context& context = contextOf(c);
    const std::string text = needName(json, "json");
    need(out, "out");
    auto network = std::make_unique<NetworkObject>();
    buildNetworkFromJson(network->network, parseJsonText(text, "network"), "network");
    *out = adopt<lodestone_network>(context, HandleKind::Network, std::move(network));
  });
}

}  // namespace lodestone::plugin::abi
