// The node registry and networks built from Python dicts.
#include <memory>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "lodestone/core/mpm/solver.h"
#include "lodestone/plugin/network.h"
#include "lodestone/plugin/network_json.h"
#include "lodestone/plugin/node_registry.h"
#include "lodestone/plugin/param_json.h"

namespace lodestone::python {

namespace {

nlohmann::json toJson(const py::handle& object) {
  const py::module_ json = py::module_::import("json");
  return nlohmann::json::parse(json.attr("dumps")(object).cast<std::string>());
}

py::dict portDict(const plugin::PortDecl& p) {
  py::dict d;
  d["name"] = p.name;
  d["type"] = plugin::toString(p.type);
  d["help"] = p.help;
  d["optional"] = p.optional;
  d["multiple"] = p.multiple;
  return d;
}

py::dict nodeDict(const plugin::NodeDecl& n) {
  py::dict d;
  d["type"] = n.type;
  d["label"] = n.label;
  d["category"] = n.category;
  d["help"] = n.help;
  py::list params, inputs, outputs;
  for (const plugin::ParamDecl& p : n.params) {
    py::dict e;
    e["name"] = p.name;
    e["type"] = plugin::toString(p.type);
    e["unit"] = p.unit;
    e["help"] = p.help;
    e["default"] = py::module_::import("json").attr("loads")(p.defaultText());
    e["range"] = p.describeRange();
    e["choices"] = p.choices;
    params.append(e);
  }
  for (const plugin::PortDecl& p : n.inputs) inputs.append(portDict(p));
  for (const plugin::PortDecl& p : n.outputs) outputs.append(portDict(p));
  d["params"] = params;
  d["inputs"] = inputs;
  d["outputs"] = outputs;
  return d;
}

// A cooked value as a dict: "type" and the value's arrays (copies) or objects.
py::dict valueDict(const plugin::NodeValue& value) {
  using namespace plugin;
  py::dict d;
  if (std::holds_alternative<std::monostate>(value)) {
    d["type"] = "none";
    return d;
  }
  d["type"] = toString(typeOf(value));
  if (const auto* p = std::get_if<std::shared_ptr<const ParticlesData>>(&value)) {
    d["positions"] = copyToNumpy((*p)->particles.x);
    d["counts"] = copyToNumpy((*p)->particles.count);
  } else if (const auto* mat = std::get_if<std::shared_ptr<const MaterialData>>(&value)) {
    d["name"] = (*mat)->name;
    d["material"] = (*mat)->material;
  } else if (const auto* s = std::get_if<std::shared_ptr<const SourcesData>>(&value)) {
    d["sources"] = std::make_shared<FieldSourceSet>((*s)->all());
  } else if (const auto* c = std::get_if<std::shared_ptr<const CollidersData>>(&value)) {
    d["count"] = (*c)->colliders.size();
  } else if (const auto* n = std::get_if<std::shared_ptr<const DensityData>>(&value)) {
    const DenseGrid<double>& g = (*n)->density;
    const py::ssize_t bytes = sizeof(double);
    const Index3 dims = g.spec().dims;
    d["density"] = py::array(py::dtype::of<double>(), {py::ssize_t(dims.i), py::ssize_t(dims.j), py::ssize_t(dims.k)},
                             {bytes, bytes * dims.i, bytes * dims.i * dims.j}, g.data());  // copied
    d["grid"] = g.spec();
    d["total_count"] = (*n)->totalCount;
  } else if (const auto* f = std::get_if<std::shared_ptr<const FieldData>>(&value)) {
    d["stage"] = (*f)->stage;
    d["report"] = (*f)->report;
  } else if (const auto* fo = std::get_if<std::shared_ptr<const ForcesData>>(&value)) {
    d["forces"] = copyToNumpy((*fo)->particleForces);
    d["total"] = fromVec3((*fo)->total);
    d["report"] = (*fo)->report;
  } else if (const auto* sim = std::get_if<std::shared_ptr<const SimulationData>>(&value)) {
    d["solver"] = (*sim)->solver;
    d["frames"] = (*sim)->frames;
    d["time"] = (*sim)->time;
    d["centre_of_mass"] = copyToNumpy((*sim)->centreOfMass);
  }
  return d;
}

}  // namespace

void bindNodes(py::module_& m) {
  m.def(
      "node_types",
      [] {
        py::list out;
        for (const plugin::NodeDecl& n : plugin::nodeRegistry()) out.append(nodeDict(n));
        return out;
      },
      "Every registered node type as a dict: type, label, category, help, params (name, type, unit, default, "
      "range, choices, help), inputs and outputs (name, type, help, optional, multiple).");
  m.def(
      "node_type", [](const std::string& type) { return nodeDict(plugin::requireNode(type)); }, py::arg("type"),
      "One node type's dict; ValueError naming an unknown type with the closest registered one.");
  m.def("vdb_built", &plugin::vdbBuilt, "Whether VDB import and export are built into this library.");

  py::class_<plugin::Network>(
      m, "Network",
      "A network of nodes (docs/nodes.md): named nodes with parameters, connections, and cooks that evaluate a "
      "node after what it depends on. Not thread-safe: one thread at a time.")
      .def(py::init<>())
      .def_static(
          "from_dict",
          [](const py::dict& doc) {
            auto n = std::make_unique<plugin::Network>();
            plugin::buildNetworkFromJson(*n, toJson(doc), "network");
            return n;
          },
          py::arg("doc"),
          "A network from a dict {'nodes': [{'name', 'type', 'params': {...}}], 'connections': [{'from', "
          "'output', 'to', 'input'}]}, checked like a scene file.")
      .def("add_node", py::overload_cast<const std::string&, const std::string&>(&plugin::Network::addNode),
           py::arg("type"), py::arg("name"), "Adds a node of a registered type.")
      .def(
          "set_params",
          [](plugin::Network& n, const std::string& node, const py::dict& params) {
            plugin::setParamsFromJson(n, node, toJson(params), "set_params");
          },
          py::arg("node"), py::arg("params"),
          "Sets parameters from a dict (keys as in scene files), checked against the declarations.")
      .def("connect", &plugin::Network::connect, py::arg("from_node"), py::arg("output"), py::arg("to_node"),
           py::arg("input"), "Connects an output to an input.")
      .def("node_names", &plugin::Network::nodeNames)
      .def(
          "cook",
          [](plugin::Network& n, const std::string& node) {
            plugin::CookOutputs outs;
            {
              py::gil_scoped_release release;
              outs = n.cook(node);
            }
            py::dict d;
            for (const auto& [name, value] : outs) d[py::str(name)] = valueDict(value);
            return d;
          },
          py::arg("node"),
          "Cooks `node` (and what it depends on) without the GIL; returns {output name: dict} with 'type' and "
          "the value: particles (positions, counts), forces (forces N, total N, report), field (stage, "
          "report), density (density 1/m^3, grid), sources (sources), simulation (solver, frames, time), ...");
}

}  // namespace lodestone::python
