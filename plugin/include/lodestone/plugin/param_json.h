#pragma once
// Node parameters from JSON: the one way a declared parameter is read from
// JSON, for scene-file entries (readNodeEntry) and for the C ABI's
// network_set_json (setParamsFromJson) alike. A value is read by the strict
// JsonReader (json_reader.h) from the declaration (type, unit, range,
// choices), so both give the scene files' messages, e.g.
//   scene.json: bodies[0].radius: expected a number in m > 0, found number -1
//   node 'ball' (particle_source): radius: expected a number in m > 0, found number -1
// and is then checked and normalised by ParamDecl::check, as every value set
// on a network is. A dotted parameter `a.b` is key `b` of the object `a`.
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodestone/plugin/json_reader.h"
#include "lodestone/plugin/network.h"
#include "lodestone/plugin/param.h"

namespace lodestone::plugin {

/// The value of key `key` of `entry` as parameter `decl` (required: throws
/// InvalidArgument "file: path.key: ..." when absent), type and range checked
/// with the reader's messages; a Direction comes back as given (non-zero),
/// ParamDecl::check normalises it.
ParamValue readParam(JsonReader& entry, const std::string& key, const ParamDecl& decl);

/// Called with each nested object of an entry (its name and reader) before it
/// is finished: it may read keys of that object that are not parameters.
using EntryGroupHook = std::function<void(const std::string& group, JsonReader& reader)>;

/// Reads the parameters of node type `nodeType` from a scene-file entry: every
/// declared parameter that applies (its condition holds for the values read
/// before it), required ones necessarily. Parameters whose names are in
/// `skip` (or start with a `skip` entry ending in '.') are left to the
/// caller. Nested objects are finished here (after `groupHook`); `entry` is
/// not (the caller may read scene-only keys, then finishes it). Absent
/// optional parameters keep their declared defaults (ParamSet::given tells).
/// Throws InvalidArgument naming the entry's path (and an unknown node type).
ParamSet readNodeEntry(JsonReader& entry, const std::string& nodeType, const std::vector<std::string>& skip = {},
                       const EntryGroupHook& groupHook = {});

/// Sets every key of the object `params` on `node` (any declared parameter,
/// whatever its condition; nested objects for dotted names). Throws
/// InvalidArgument "where: path: ..." for a value of the wrong type or out of
/// range, and for an unknown key with the closest declared name; nothing is
/// set then.
void setParamsFromJson(Network& network, const std::string& node, const nlohmann::json& params,
                       const std::string& where);

}  // namespace lodestone::plugin
