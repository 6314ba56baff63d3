#pragma once
// Node parameter values from JSON: a value of a declared parameter's JSON
// type (number, integer, boolean, string, 3-array, array of numbers), and a
// whole object of parameters set on a network node. Nested objects map onto
// dotted parameter names ({"magnetic": {"law": "paper"}} sets
// `magnetic.law`).
#include <string>

#include <nlohmann/json.hpp>

#include "lodestone/plugin/network.h"
#include "lodestone/plugin/param.h"

namespace lodestone::plugin {

/// Converts `value` to the declared parameter's type (range checked later by
/// ParamDecl::check); throws InvalidArgument "<where>: <name>: expected ...".
ParamValue paramFromJson(const ParamDecl& decl, const nlohmann::json& value, const std::string& where);

/// Sets every key of the object `params` on `node`; unknown keys are rejected
/// naming the closest declared parameter.
void setParamsFromJson(Network& network, const std::string& node, const nlohmann::json& params,
                       const std::string& where);

}  // namespace lodestone::plugin
