#pragma once
// The entries of the C ABI's table: each member of lodestone_api and the
// function behind it, in the table's order. Each function is declared here
// with its member's exact type (so a definition that drifts from the header's
// signature does not link) and defined in the file of its part: library.cpp,
// fields.cpp, stage.cpp, nodes.cpp or network.cpp. get_api.cpp fills the table
// from this one list.
#include <type_traits>

#include "lodestone/plugin/lodestone.h"

#define LODESTONE_ABI_ENTRIES(X) \
  X(version_string, versionString) \
  X(status_string, statusString) \
  X(thread_last_error, threadLastError) \
  X(has_vdb, hasVdb) \
  X(context_create, contextCreate) \
  X(context_destroy, contextDestroy) \
  X(context_last_error, contextLastError) \
  X(fields_create, fieldsCreate) \
  X(fields_destroy, fieldsDestroy) \
  X(fields_add_uniform, fieldsAddUniform) \
  X(fields_add_dipole, fieldsAddDipole) \
  X(fields_add_sphere_magnet, fieldsAddSphere) \
  X(fields_add_box_magnet, fieldsAddBox) \
  X(fields_add_cylinder_magnet, fieldsAddCylinder) \
  X(fields_add_vdb, fieldsAddVdb) \
  X(fields_count, fieldsCount) \
  X(fields_evaluate, fieldsEvaluate) \
  X(stage_params_default, stageParamsDefault) \
  X(stage_create, stageCreate) \
  X(stage_destroy, stageDestroy) \
  X(stage_grid, stageGrid) \
  X(stage_run_particles, stageRunParticles) \
  X(stage_run_density, stageRunDensity) \
  X(stage_particle_forces, stageParticleForces) \
  X(stage_sample, stageSample) \
  X(stage_read_field, stageReadField) \
  X(stage_report, stageReport) \
  X(stage_report_json, stageReportJson) \
  X(stage_export_vdb, stageExportVdb) \
  X(node_type_count, nodeTypeCount) \
  X(node_type_info, nodeTypeInfo) \
  X(node_param_info, nodeParamInfo) \
  X(node_input_info, nodeInputInfo) \
  X(node_output_info, nodeOutputInfo) \
  X(network_create, networkCreate) \
  X(network_destroy, networkDestroy) \
  X(network_add_node, networkAddNode) \
  X(network_set_float, networkSetFloat) \
  X(network_set_int, networkSetInt) \
  X(network_set_bool, networkSetBool) \
  X(network_set_string, networkSetString) \
  X(network_set_vec3, networkSetVec3) \
  X(network_set_json, networkSetJson) \
  X(network_connect, networkConnect) \
  X(network_cook, networkCook) \
  X(network_output_json, networkOutputJson) \
  X(network_read_positions, networkReadPositions) \
  X(stage_number_density, stageNumberDensity) \
  X(network_set_particles, networkSetParticles) \
  X(network_read_forces, networkReadForces) \
  X(network_create_from_json, networkCreateFromJson)

namespace lodestone::plugin::abi {

#define LODESTONE_ABI_DECLARE(member, function) std::remove_pointer_t<decltype(lodestone_api::member)> function;
LODESTONE_ABI_ENTRIES(LODESTONE_ABI_DECLARE)
#undef LODESTONE_ABI_DECLARE

}  // namespace lodestone::plugin::abi
