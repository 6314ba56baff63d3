#pragma once
// Scene-file entries as node parameters: an entry of materials[], bodies[],
// magnets[], fields[] or colliders[] is a node (material, particle_source,
// magnet, applied_field, collider) whose keys are that node's declared
// parameters. readNodeEntry reads and checks every declared parameter that
// applies, with the strict JsonReader (same messages: the path of the entry,
// the unit and range expected, the value found), a dotted parameter `a.b`
// being key `b` of the entry's object `a`.
#include <string>
#include <vector>

#include "json_schema.h"
#include "lodestone/plugin/param.h"

namespace lodestone::examples {

/// Reads the parameters of node type `nodeType` from `entry`. Parameters
/// whose names are in `skip` (or start with a `skip` entry ending in '.')
/// are left to the caller. Nested objects are finished here; `entry` is not
/// (the caller may read scene-only keys, then finishes it). Absent optional
/// parameters keep their declared defaults (ParamSet::given tells).
plugin::ParamSet readNodeEntry(JsonReader& entry, const std::string& nodeType,
                               const std::vector<std::string>& skip = {});

}  // namespace lodestone::examples
